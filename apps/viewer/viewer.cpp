#include "viewer.h"

#include "camera_controls.h"
#include "render_worker.h"
#include "tf_editor.h"
#include "view_script.h"

#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/settings.h>

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace uvr {

namespace {

constexpr float kPanelWidth = 360.f;
constexpr float kLegendWidth = 110.f;
constexpr float kOrbitDegreesPerPixel = 0.4f;

/// What the controls edit; a change of anything but `heatmap` asks the worker for a new frame.
struct Controls {
  Camera camera;
  ColorMap colorMap;
  ValueRange range;
  RenderMode mode = RenderMode::Full;
  float s1 = 0.f, s2 = 0.f, p = 0.f; ///< 0: the default
  bool shade = false;
  /// Isosurfaces: drawn or not, the first one's value (the others as --iso gave them), the volume hidden.
  bool iso = false;
  float isoValue = 0.f;
  bool isoOnly = false;
  bool heatmap = false;
};

bool sameView(const ViewState &a, const ViewState &b) {
  const auto sameVec = [](Vec3f u, Vec3f v) { return u.x == v.x && u.y == v.y && u.z == v.z; };
  const FrameSettings &i = a.settings, &j = b.settings;
  return sameVec(a.camera.eye, b.camera.eye) && sameVec(a.camera.at, b.camera.at) &&
         sameVec(a.camera.up, b.camera.up) && a.camera.fovy == b.camera.fovy &&
         a.colorMap.rgbPoints == b.colorMap.rgbPoints &&
         a.colorMap.opacityPoints == b.colorMap.opacityPoints &&
         a.colorMap.colorSpace == b.colorMap.colorSpace && a.range.min == b.range.min &&
         a.range.max == b.range.max && i.mode == j.mode && i.s1 == j.s1 && i.s2 == j.s2 && i.p == j.p &&
         i.unit == j.unit && i.shade == j.shade && i.isoValues == j.isoValues && i.isoOnly == j.isoOnly &&
         a.settings.width == b.settings.width && a.settings.height == b.settings.height;
}

nlohmann::json vectorJson(Vec3f v) { return {v.x, v.y, v.z}; }

/// The GL texture the frame is shown from.
class FrameTexture {
public:
  FrameTexture() { glGenTextures(1, &id_); }
  ~FrameTexture() { glDeleteTextures(1, &id_); }
  void upload(const Image &image, bool smooth) {
    glBindTexture(GL_TEXTURE_2D, id_);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, smooth ? GL_LINEAR : GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, smooth ? GL_LINEAR : GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, image.width, image.height, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 image.rgb.data());
  }
  ImTextureID id() const { return reinterpret_cast<ImTextureID>(static_cast<intptr_t>(id_)); }

private:
  GLuint id_ = 0;
};

/// The window's pixels, top row first.
Image readWindow(int width, int height) {
  Image image(width, height);
  std::vector<uint8_t> rows(image.rgb.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  const size_t stride = size_t(width) * 3;
  for (int y = 0; y < height; ++y)
    std::copy_n(&rows[size_t(height - 1 - y) * stride], stride, &image.rgb[size_t(y) * stride]);
  return image;
}

class Viewer {
public:
  Viewer(const ViewerSetup &setup, GLFWwindow *window)
      : setup_(setup), window_(window), renderer_(setup.mesh, setup.fieldIndex, setup.leafSize),
        worker_(renderer_, [] { glfwPostEmptyEvent(); }) {
    controls_.camera = setup.camera;
    controls_.colorMap = setup.colorMap;
    makeOpacityPointsExplicit(controls_.colorMap);
    controls_.range = setup.range;
    controls_.mode = setup.settings.mode;
    controls_.s1 = setup.settings.s1;
    controls_.s2 = setup.settings.s2;
    controls_.p = setup.settings.p;
    controls_.shade = setup.settings.shade;
    controls_.iso = !setup.settings.isoValues.empty();
    controls_.isoValue =
        controls_.iso ? setup.settings.isoValues[0] : 0.5f * (setup.range.min + setup.range.max);
    controls_.isoOnly = setup.settings.isoOnly;
    presets_ = builtinColorMapNames();
    for (const ColorMap &map : setup.presets)
      presets_.push_back(map.name);
    if (!setup.script.empty())
      script_ = readViewScript(setup.script);
    scripted_ = !setup.script.empty();
    std::snprintf(presetPath_, sizeof presetPath_, "%s", "preset.json");
  }

  void run() {
    while (!glfwWindowShouldClose(window_)) {
      // Sleep until input or a finished frame (the worker posts an event); scripts run one command per frame.
      glfwWaitEventsTimeout(scripted_ && !waitingForScreenshot_ ? 0.0 : 0.25);
      receiveFrame();
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      drawPanel();
      handleMouse();
      const bool screenshotNow = scripted_ && stepScript();
      submitIfChanged();
      drawImageAndLegend();
      ImGui::Render();
      int width, height;
      glfwGetFramebufferSize(window_, &width, &height);
      glViewport(0, 0, width, height);
      glClearColor(0.08f, 0.08f, 0.09f, 1.f);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      if (screenshotNow)
        writeScreenshot(width, height);
      glfwSwapBuffers(window_);
    }
  }

private:
  /// The image region: the window between the panel and the legend.
  void regionSize(int &width, int &height) const {
    int w, h;
    glfwGetFramebufferSize(window_, &w, &h);
    width = std::max(1, w - int(kPanelWidth) - int(kLegendWidth));
    height = std::max(1, h);
  }

  ViewState currentState() const {
    ViewState state;
    state.camera = controls_.camera;
    state.colorMap = controls_.colorMap;
    state.range = controls_.range;
    state.settings = setup_.settings;
    regionSize(state.settings.width, state.settings.height);
    state.settings.mode = controls_.mode;
    state.settings.s1 = controls_.s1;
    state.settings.s2 = controls_.s2;
    state.settings.p = controls_.p;
    state.settings.shade = controls_.shade;
    if (controls_.iso) {
      if (state.settings.isoValues.empty())
        state.settings.isoValues.push_back(controls_.isoValue);
      state.settings.isoValues[0] = controls_.isoValue;
    } else {
      state.settings.isoValues.clear();
    }
    state.settings.isoOnly = controls_.iso && controls_.isoOnly;
    state.settings = withDefaultSampling(state.settings, setup_.defaultStep, setup_.defaultUnit);
    return state;
  }

  void submitIfChanged() {
    const ViewState state = currentState();
    if (submittedVersion_ != 0 && sameView(state, submitted_))
      return;
    submitted_ = state;
    submittedVersion_ = worker_.submit(state);
  }

  void receiveFrame() {
    std::optional<ViewerFrame> frame = worker_.take();
    if (!frame)
      return;
    shown_ = std::move(*frame);
    showImage();
  }

  void showImage() {
    if (!shown_.error.empty() || shown_.frame.image.width == 0)
      return;
    const Image &image = controls_.heatmap ? heatmap() : shown_.frame.image;
    texture_.upload(image, shown_.scale != 1);
  }

  const Image &heatmap() {
    if (heatmapVersion_ != shown_.version || heatmapScale_ != shown_.scale) {
      heatmap_ =
          heatmapImage(shown_.frame.samplesPerPixel, shown_.frame.image.width, shown_.frame.image.height);
      heatmapVersion_ = shown_.version;
      heatmapScale_ = shown_.scale;
    }
    return heatmap_;
  }

  void handleMouse() {
    const ImGuiIO &io = ImGui::GetIO();
    int width, height;
    regionSize(width, height);
    const bool overImage = io.MousePos.x >= kPanelWidth && io.MousePos.x < kPanelWidth + float(width) &&
                           io.MousePos.y >= 0.f && io.MousePos.y < float(height);
    if (io.WantCaptureMouse)
      return;
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left) || ImGui::IsMouseClicked(ImGuiMouseButton_Right) ||
        ImGui::IsMouseClicked(ImGuiMouseButton_Middle))
      dragging_ = overImage;
    if (!ImGui::IsAnyMouseDown())
      dragging_ = false;
    const ImVec2 d = io.MouseDelta;
    if (dragging_ && (d.x != 0.f || d.y != 0.f)) {
      const bool panning = ImGui::IsMouseDown(ImGuiMouseButton_Right) ||
                           ImGui::IsMouseDown(ImGuiMouseButton_Middle) || io.KeyShift;
      if (panning)
        controls_.camera = pan(controls_.camera, d.x / float(height), -d.y / float(height));
      else
        controls_.camera = orbit(controls_.camera, -d.x * kOrbitDegreesPerPixel, d.y * kOrbitDegreesPerPixel);
    }
    if (overImage && io.MouseWheel != 0.f)
      controls_.camera = zoom(controls_.camera, std::pow(1.1f, io.MouseWheel));
  }

  void choosePreset(const std::string &name) {
    ColorMap map;
    const auto fromFile = std::find_if(setup_.presets.begin(), setup_.presets.end(),
                                       [&](const ColorMap &m) { return m.name == name; });
    map = fromFile != setup_.presets.end() ? *fromFile : builtinColorMap(name);
    if (map.opacityPoints.empty()) {
      // Keep the edited opacity, carried over to the new preset's x span.
      const ColorMap &old = controls_.colorMap;
      const float oldLow = old.rgbPoints.front(), oldHigh = old.rgbPoints[old.rgbPoints.size() - 4];
      const float low = map.rgbPoints.front(), high = map.rgbPoints[map.rgbPoints.size() - 4];
      map.opacityPoints = old.opacityPoints;
      for (size_t i = 0; i < map.opacityPoints.size(); i += 4)
        map.opacityPoints[i] = low + (map.opacityPoints[i] - oldLow) /
                                         (oldHigh > oldLow ? oldHigh - oldLow : 1.f) * (high - low);
    }
    controls_.colorMap = map;
  }

  void drawPanel() {
    int width, height;
    glfwGetFramebufferSize(window_, &width, &height);
    ImGui::SetNextWindowPos({0.f, 0.f});
    ImGui::SetNextWindowSize({kPanelWidth, float(height)});
    ImGui::Begin("uvr", nullptr,
                 ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                     ImGuiWindowFlags_NoTitleBar);
    const FieldInfo field = setup_.mesh.field(setup_.fieldIndex);
    ImGui::TextWrapped("%s", setup_.meshPath.c_str());
    ImGui::Text("%llu cells, field %s (%s)", static_cast<unsigned long long>(setup_.mesh.cellCount()),
                field.name.c_str(), field.centering == Centering::Point ? "point" : "cell");
    ImGui::Separator();

    // Statistics of the frame on screen.
    if (!shown_.error.empty()) {
      ImGui::TextColored({1.f, 0.4f, 0.4f, 1.f}, "%s", shown_.error.c_str());
    } else if (!shown_.stats.is_null()) {
      const nlohmann::json &s = shown_.stats;
      ImGui::Text("Frame: %.0f ms at %dx%d (%s)", s["render_ms"].get<double>(), s["width"].get<int>(),
                  s["height"].get<int>(), shown_.scale == 1 ? "full resolution" : "preview, 1/4");
      ImGui::Text("Samples/pixel: %.1f mean, %u max", s["samples_per_pixel_mean"].get<double>(),
                  s["samples_per_pixel_max"].get<unsigned>());
      ImGui::Text("Partitions skipped: %u of %u", s["partitions_skipped"].get<unsigned>(),
                  s["partitions"].get<unsigned>());
      // tf_update_ms as everywhere: the update this frame waited for, 0 when the function is unchanged.
      ImGui::Text("TF update: %.2f ms, UI: %.0f fps", s["tf_update_ms"].get<double>(),
                  double(ImGui::GetIO().Framerate));
    }
    ImGui::Checkbox("Samples heat map", &controls_.heatmap);
    if (controls_.heatmap != heatmapShown_) {
      heatmapShown_ = controls_.heatmap;
      showImage();
    }
    ImGui::Separator();

    // Sampling.
    int mode = int(controls_.mode);
    const char *modes[] = {"reference", "skip", "adaptive", "full"};
    for (int i = 0; i < 4; ++i)
      if (parseMode(modes[i]) == controls_.mode)
        mode = i;
    ImGui::SetNextItemWidth(150.f);
    if (ImGui::Combo("Mode", &mode, modes, 4))
      controls_.mode = parseMode(modes[mode]);
    ImGui::Checkbox("Shade", &controls_.shade);
    ImGui::Checkbox("Isosurface", &controls_.iso);
    if (controls_.iso) {
      ImGui::SameLine();
      ImGui::Checkbox("alone", &controls_.isoOnly);
      ImGui::SetNextItemWidth(150.f);
      const float span = controls_.range.max - controls_.range.min;
      ImGui::DragFloat("Iso value", &controls_.isoValue, 0.002f * span, controls_.range.min,
                       controls_.range.max, "%.4g");
    }
    const float step = setup_.defaultStep;
    ImGui::SetNextItemWidth(150.f);
    ImGui::DragFloat("s1", &controls_.s1, step * 0.01f, step * 0.05f, step * 16.f, "%.4g");
    ImGui::SetNextItemWidth(150.f);
    ImGui::DragFloat("s2", &controls_.s2, step * 0.05f, controls_.s1, step * 64.f, "%.4g");
    ImGui::SetNextItemWidth(150.f);
    ImGui::DragFloat("p", &controls_.p, 0.05f, 1.f, 16.f, "%.2f");
    controls_.s2 = std::max(controls_.s2, controls_.s1);
    if (ImGui::Button("Default sampling")) {
      const FrameSettings d = withDefaultSampling({}, step);
      controls_.s1 = d.s1;
      controls_.s2 = d.s2;
      controls_.p = d.p;
    }
    ImGui::SameLine();
    if (ImGui::Button("Reset camera"))
      controls_.camera = setup_.camera;
    // ParaView's view-direction buttons: the side the camera looks from, framed as the reset camera.
    ImGui::Text("View from");
    for (const std::string &name : cameraViewNames()) {
      ImGui::SameLine();
      if (ImGui::Button(name.c_str()))
        controls_.camera = viewCamera(name);
    }
    ImGui::Separator();

    // Transfer function.
    ImGui::Text("Transfer function");
    ImGui::SetNextItemWidth(kPanelWidth - 90.f);
    if (ImGui::BeginCombo("Preset", controls_.colorMap.name.c_str())) {
      for (const std::string &name : presets_)
        if (ImGui::Selectable(name.c_str(), name == controls_.colorMap.name))
          choosePreset(name);
      ImGui::EndCombo();
    }
    transferFunctionEditor(controls_.colorMap, kPanelWidth - 24.f, 110.f);
    ImGui::TextDisabled("Drag a point; double-click adds one,");
    ImGui::TextDisabled("right-click removes it");
    float range[2] = {controls_.range.min, controls_.range.max};
    const ValueRange data = setup_.mesh.fieldRange(setup_.fieldIndex);
    const float speed = std::max(1e-6f, (data.max - data.min) * 0.002f);
    ImGui::SetNextItemWidth(kPanelWidth - 90.f);
    if (ImGui::DragFloat2("Range", range, speed, 0.f, 0.f, "%.4g") && range[1] > range[0])
      controls_.range = {range[0], range[1]};
    if (ImGui::Button("Data range"))
      controls_.range = data;
    ImGui::SetNextItemWidth(kPanelWidth - 90.f);
    ImGui::InputText("File", presetPath_, sizeof presetPath_);
    if (ImGui::Button("Load preset"))
      loadPreset();
    ImGui::SameLine();
    if (ImGui::Button("Save preset"))
      savePreset();
    if (!presetMessage_.empty())
      ImGui::TextWrapped("%s", presetMessage_.c_str());
    ImGui::Separator();
    ImGui::TextDisabled("Left drag: orbit   Right or Shift drag: pan");
    ImGui::TextDisabled("Wheel: zoom");
    ImGui::End();
  }

  void loadPreset() {
    try {
      std::vector<ColorMap> maps = readColorMapPresets(presetPath_);
      for (const ColorMap &map : maps)
        if (std::find(presets_.begin(), presets_.end(), map.name) == presets_.end()) {
          presets_.push_back(map.name);
          setup_.presets.push_back(map);
        }
      choosePreset(maps.front().name);
      presetMessage_ = "Loaded " + std::to_string(maps.size()) + " preset(s)";
    } catch (const std::exception &e) {
      presetMessage_ = e.what();
    }
  }

  void savePreset() {
    try {
      writeColorMapFile(presetPath_, controls_.colorMap);
      presetMessage_ = std::string("Saved ") + presetPath_;
    } catch (const std::exception &e) {
      presetMessage_ = e.what();
    }
  }

  void drawImageAndLegend() {
    int width, height;
    regionSize(width, height);
    ImDrawList *draw = ImGui::GetBackgroundDrawList();
    const Vec3f bg = setup_.settings.background;
    draw->AddRectFilled({kPanelWidth, 0.f}, {kPanelWidth + float(width), float(height)},
                        ImGui::ColorConvertFloat4ToU32({bg.x, bg.y, bg.z, 1.f}));
    if (shown_.error.empty() && shown_.frame.image.width > 0)
      draw->AddImage(texture_.id(), {kPanelWidth, 0.f}, {kPanelWidth + float(width), float(height)});
    const ImVec2 corner{kPanelWidth + float(width), 0.f};
    if (controls_.heatmap) {
      draw->AddRectFilled(corner, {corner.x + kLegendWidth, float(height)}, IM_COL32(32, 32, 36, 255));
      draw->AddText({corner.x + 8.f, 8.f}, IM_COL32(235, 235, 235, 255), "Samples");
      draw->AddText({corner.x + 8.f, 8.f + ImGui::GetTextLineHeight()}, IM_COL32(235, 235, 235, 255),
                    "per pixel:");
      draw->AddText({corner.x + 8.f, 8.f + 2.f * ImGui::GetTextLineHeight()}, IM_COL32(235, 235, 235, 255),
                    "scale in");
      draw->AddText({corner.x + 8.f, 8.f + 3.f * ImGui::GetTextLineHeight()}, IM_COL32(235, 235, 235, 255),
                    "the image");
    } else {
      colorLegend(draw, controls_.colorMap, controls_.range, setup_.mesh.field(setup_.fieldIndex).name,
                  corner, {kLegendWidth, float(height)});
    }
  }

  /// The named view of the mesh for the image region's aspect, at the current vertical view angle.
  Camera viewCamera(const std::string &name) const {
    int width, height;
    regionSize(width, height);
    return frameBounds(setup_.mesh.bounds(), name, controls_.camera.fovy, float(width) / float(height));
  }

  /// Applies script commands up to the next screenshot; returns true when this frame is to be captured.
  bool stepScript() {
    if (waitingForScreenshot_) {
      if (!shown_.error.empty() && shown_.version == submittedVersion_)
        throw Error(setup_.script, "line " + std::to_string(script_[next_ - 1].line), shown_.error);
      return shown_.version == submittedVersion_ && shown_.scale == 1;
    }
    if (next_ >= script_.size()) {
      glfwSetWindowShouldClose(window_, GLFW_TRUE);
      return false;
    }
    const ScriptCommand &c = script_[next_++];
    const std::vector<float> &n = c.numbers;
    try {
      if (c.name == "orbit")
        controls_.camera = orbit(controls_.camera, n[0], n[1]);
      else if (c.name == "pan")
        controls_.camera = pan(controls_.camera, n[0], n[1]);
      else if (c.name == "zoom")
        controls_.camera = zoom(controls_.camera, n[0]);
      else if (c.name == "reset-camera")
        controls_.camera = setup_.camera;
      else if (c.name == "view")
        controls_.camera = viewCamera(c.words[0]);
      else if (c.name == "mode")
        controls_.mode = parseMode(c.words[0]);
      else if (c.name == "s1" || c.name == "s2" || c.name == "p") {
        const FrameSettings d = withDefaultSampling({}, setup_.defaultStep);
        float &value = c.name == "s1" ? controls_.s1 : c.name == "s2" ? controls_.s2 : controls_.p;
        value = n[0] > 0.f ? n[0] : (c.name == "s1" ? d.s1 : c.name == "s2" ? d.s2 : d.p);
      } else if (c.name == "preset") {
        std::string name = c.words[0];
        for (size_t i = 1; i < c.words.size(); ++i)
          name += " " + c.words[i];
        if (std::find(presets_.begin(), presets_.end(), name) == presets_.end())
          builtinColorMap(name); // throws, listing the names
        choosePreset(name);
      } else if (c.name == "range")
        controls_.range = {n[0], n[1]};
      else if (c.name == "opacity") {
        // Values of the field, mapped onto the preset's x span as the range stretches it.
        ColorMap &map = controls_.colorMap;
        const float low = map.rgbPoints.front(), high = map.rgbPoints[map.rgbPoints.size() - 4];
        const ValueRange r = controls_.range;
        map.opacityPoints.clear();
        for (size_t i = 0; i < n.size(); i += 2) {
          const float x = r.max > r.min ? low + (n[i] - r.min) / (r.max - r.min) * (high - low) : low;
          map.opacityPoints.insert(map.opacityPoints.end(), {std::clamp(x, low, high), n[i + 1], 0.5f, 0.f});
        }
      } else if (c.name == "heatmap") {
        controls_.heatmap = c.words[0] == "on";
      } else if (c.name == "screenshot") {
        screenshotName_ = c.words[0];
        waitingForScreenshot_ = true;
      }
    } catch (const Error &e) {
      throw Error(setup_.script, "line " + std::to_string(c.line), e.what());
    }
    return false;
  }

  void writeScreenshot(int windowWidth, int windowHeight) {
    waitingForScreenshot_ = false;
    if (setup_.screenshotPrefix.empty())
      return;
    const std::string base = setup_.screenshotPrefix + "-" + screenshotName_;
    writePng(base + ".png", readWindow(windowWidth, windowHeight));
    writePng(base + "-frame.png", controls_.heatmap ? heatmap() : shown_.frame.image);
    writeColorMapFile(base + "-tf.json", controls_.colorMap);
    const FrameSettings &is = submitted_.settings;
    const nlohmann::json view = {
        {"camera",
         {{"eye", vectorJson(controls_.camera.eye)},
          {"at", vectorJson(controls_.camera.at)},
          {"up", vectorJson(controls_.camera.up)},
          {"fovy", controls_.camera.fovy}}},
        {"mode", modeName(is.mode)},
        {"s1", is.s1},
        {"s2", is.s2},
        {"p", is.p},
        {"unit", is.unit},
        {"range", {controls_.range.min, controls_.range.max}},
        {"preset", controls_.colorMap.name},
        {"heatmap", controls_.heatmap},
        {"image_region", {int(kPanelWidth), 0, submitted_.settings.width, submitted_.settings.height}},
        {"window", {windowWidth, windowHeight}},
        {"stats", shown_.stats},
    };
    std::ofstream out(base + ".json");
    out << view.dump(2) << '\n';
    if (!out)
      throw Error(base + ".json", "", "cannot write the view");
  }

  ViewerSetup setup_;
  GLFWwindow *window_;
  VolumeRenderer renderer_;
  RenderWorker worker_;
  FrameTexture texture_;
  Controls controls_;
  std::vector<std::string> presets_;
  char presetPath_[512] = {};
  std::string presetMessage_;

  ViewState submitted_;
  uint64_t submittedVersion_ = 0;
  ViewerFrame shown_;
  Image heatmap_;
  uint64_t heatmapVersion_ = 0;
  int heatmapScale_ = 0;
  bool heatmapShown_ = false;
  bool dragging_ = false;

  std::vector<ScriptCommand> script_;
  bool scripted_ = false;
  size_t next_ = 0;
  bool waitingForScreenshot_ = false;
  std::string screenshotName_;
};

/// GLFW and Dear ImGui for the lifetime of the viewer.
class Window {
public:
  Window(int width, int height, const std::string &title) {
    glfwSetErrorCallback([](int, const char *text) { std::fprintf(stderr, "uvr: GLFW: %s\n", text); });
    if (!glfwInit())
      throw Error("cannot open a window (no display? run under xvfb-run for scripts)");
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
      glfwTerminate();
      throw Error("cannot create an OpenGL 3.0 window");
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 130");
  }
  ~Window() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  GLFWwindow *get() const { return window_; }

private:
  GLFWwindow *window_ = nullptr;
};

} // namespace

void runViewer(const ViewerSetup &setup) {
  Window window(int(kPanelWidth + kLegendWidth) + setup.settings.width, setup.settings.height,
                "uvr view - " + setup.meshPath);
  Viewer viewer(setup, window.get());
  viewer.run();
}

} // namespace uvr
