#include "commands.h"

#include "core/error.h"
#include "core/timer.h"
#include "image/image.h"
#include "io/mesh_io.h"
#include "mesh/mesh_stats.h"
#include "render/renderer.h"

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace uvr {

namespace {

struct RenderOptions {
  std::string mesh;
  std::string field;
  std::string tf;
  std::string tfName;
  std::vector<float> range;
  std::string mode = "full";
  float s1 = 0.f, s2 = 0.f, p = 0.f, unit = 0.f;
  uint32_t leafSize = kDefaultLeafSize;
  std::string size = "1024x1024";
  std::string eye, at, up;
  float fovy = 30.f;
  std::string background = "0,0,0";
  int frames = 1;
  std::string backend = "cpu";
  std::string output;
  std::string heatmap;
  std::string stats;
};

/// Defaults measured on the brain meshes (README, "Choosing defaults"): s2 = kDefaultS2Factor * s1.
constexpr float kDefaultS2Factor = 8.f;
constexpr float kDefaultP = 4.f;

Vec3f parseVector(const std::string &text, const std::string &option) {
  Vec3f v;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',' || !in.eof())
    throw Error("--" + option + " expects X,Y,Z, got '" + text + "'");
  return v;
}

void parseSize(const std::string &text, int &width, int &height) {
  char x = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || x != 'x' || !in.eof() || width <= 0 || height <= 0 || width > 16384 ||
      height > 16384)
    throw Error("--size expects WxH with each side from 1 to 16384, got '" + text + "'");
}

ColorMap chooseColorMap(const RenderOptions &o) {
  if (o.tf.empty())
    return builtinColorMap(builtinColorMapNames().front());
  if (std::filesystem::exists(o.tf))
    return readColorMapFile(o.tf, o.tfName);
  if (o.tf.size() > 5 && o.tf.substr(o.tf.size() - 5) == ".json")
    throw Error(o.tf, "", "cannot open transfer-function file");
  return builtinColorMap(o.tf);
}

int chooseField(const Mesh &mesh, const std::string &name, const std::string &path) {
  if (mesh.fields.empty())
    throw Error(path, "", "the mesh has no scalar field to render");
  if (name.empty())
    return 0;
  const int index = mesh.findField(name);
  if (index < 0) {
    std::string names;
    for (const ScalarField &f : mesh.fields)
      names += (names.empty() ? "" : ", ") + f.name;
    throw Error(path, "", "no field named '" + name + "'; fields: " + names);
  }
  return index;
}

void writeStats(const std::string &path, const nlohmann::json &stats) {
  std::ofstream out(path);
  out << stats.dump(2) << '\n';
  if (!out)
    throw Error(path, "", "cannot write statistics");
}

void runRender(const RenderOptions &o) {
  int width, height;
  parseSize(o.size, width, height);
  if (o.backend != "cpu")
    throw Error("unknown backend '" + o.backend + "': this build has cpu");
  if (o.frames < 1)
    throw Error("--frames must be at least 1");
  const RenderMode mode = parseMode(o.mode);

  const Timer loadTimer;
  const Mesh mesh = loadMesh(o.mesh);
  const double loadMs = loadTimer.milliseconds();
  if (mesh.skippedCells > 0)
    std::fprintf(stderr, "uvr: %s: skipped %llu lower-dimensional cells\n", o.mesh.c_str(),
                 static_cast<unsigned long long>(mesh.skippedCells));
  if (mesh.cellCount() == 0)
    throw Error(o.mesh, "", "the file holds no volume cells (tetra, hexahedron, wedge or pyramid)");
  const int fieldIndex = chooseField(mesh, o.field, o.mesh);

  RenderSettings settings;
  settings.width = width;
  settings.height = height;
  settings.background = parseVector(o.background, "background");
  const float typicalStep = defaultStepSize(volumeStats(mesh));
  IntegratorSettings &is = settings.integrator;
  is.mode = mode;
  is.s1 = o.s1 > 0.f ? o.s1 : typicalStep;
  is.s2 = o.s2 > 0.f ? o.s2 : std::max(kDefaultS2Factor * typicalStep, is.s1);
  is.p = o.p > 0.f ? o.p : kDefaultP;
  is.unit = o.unit > 0.f ? o.unit : typicalStep;

  Renderer renderer(mesh, fieldIndex, o.leafSize);

  ValueRange range = valueRange(mesh.fields[size_t(fieldIndex)]);
  if (!o.range.empty())
    range = {o.range[0], o.range[1]};
  renderer.setTransferFunction(TransferFunction(chooseColorMap(o), range.min, range.max));

  const Box3f bounds = mesh.bounds();
  Camera camera = frameBounds(bounds, o.fovy, float(width) / float(height));
  if (!o.at.empty())
    camera.at = parseVector(o.at, "at");
  if (!o.eye.empty())
    camera.eye = parseVector(o.eye, "eye");
  if (!o.up.empty())
    camera.up = parseVector(o.up, "up");
  if (length(cross(camera.at - camera.eye, camera.up)) == 0.f)
    throw Error("--eye, --at and --up must not be collinear");

  std::vector<double> times;
  Frame frame;
  for (int i = 0; i < o.frames; ++i) {
    const Timer timer;
    frame = renderer.render(camera, settings);
    times.push_back(timer.milliseconds());
  }
  std::sort(times.begin(), times.end());
  const double renderMs = times[times.size() / 2];

  writePng(o.output, frame.image);
  if (!o.heatmap.empty())
    writePng(o.heatmap, heatmapImage(frame.samplesPerPixel, width, height));

  const double pixels = double(width) * double(height);
  const bool skipping = mode == RenderMode::Skip || mode == RenderMode::Full;
  std::fprintf(stderr, "uvr: %s %dx%d, %llu cells, %u partitions, %.1f samples/pixel, %.1f ms/frame\n",
               modeName(mode), width, height, static_cast<unsigned long long>(mesh.cellCount()),
               renderer.partitions().count(), double(frame.samplesTotal) / pixels, renderMs);
  if (!o.stats.empty()) {
    nlohmann::json stats = {
        {"mode", modeName(mode)},
        {"width", width},
        {"height", height},
        {"cells", mesh.cellCount()},
        {"partitions", renderer.partitions().count()},
        {"partitions_skipped", skipping ? renderer.metadata().transparentCount : 0},
        {"samples_total", frame.samplesTotal},
        {"samples_per_pixel_mean", double(frame.samplesTotal) / pixels},
        {"samples_per_pixel_max", frame.samplesMax},
        {"load_ms", loadMs},
        {"build_ms", renderer.buildMs()},
        {"tf_update_ms", renderer.tfUpdateMs()},
        {"render_ms", renderMs},
        {"frames", o.frames},
        {"s1", is.s1},
        {"s2", is.s2},
        {"p", is.p},
        {"unit", is.unit},
        {"leaf_size", o.leafSize},
        {"field", mesh.fields[size_t(fieldIndex)].name},
        {"range", {range.min, range.max}},
        {"backend", o.backend},
        {"threads", tbb::info::default_concurrency()},
    };
    writeStats(o.stats, stats);
  }
}

} // namespace

void addRenderCommand(CLI::App &app) {
  auto options = std::make_shared<RenderOptions>();
  RenderOptions &o = *options;
  CLI::App *cmd = app.add_subcommand("render", "Render a mesh to a PNG");
  cmd->add_option("MESH", o.mesh, "Mesh file (.vtu, .vtk)")->required();
  cmd->add_option("--field", o.field, "Scalar field to render (default: the first)");
  cmd->add_option("--tf", o.tf, "Transfer function: a ParaView preset JSON file or a built-in name");
  cmd->add_option("--tf-name", o.tfName, "Preset to take from the --tf file (default: the first)");
  cmd->add_option("--range", o.range, "Scalar range the transfer function spans (default: the field's)")
      ->expected(2);
  cmd->add_option("--mode", o.mode, "reference | skip | adaptive | full")
      ->check(CLI::IsMember({"reference", "skip", "adaptive", "full"}))
      ->capture_default_str();
  cmd->add_option("--s1", o.s1, "Smallest (and fixed) step (default: cube root of the median cell volume)");
  cmd->add_option("--s2", o.s2, "Largest adaptive step (default: 8 * the default s1)");
  cmd->add_option("--p", o.p, "Adaptive power, >= 1 (default: 4)");
  cmd->add_option("--unit", o.unit, "Opacity unit distance (default: the default s1)");
  cmd->add_option("--leaf-size", o.leafSize, "Most cells per partition")->capture_default_str();
  cmd->add_option("--size", o.size, "Image size WxH")->capture_default_str();
  cmd->add_option("--eye", o.eye, "Camera position X,Y,Z (default: framing the mesh from +z)");
  cmd->add_option("--at", o.at, "Focal point X,Y,Z (default: the centre of the mesh bounds)");
  cmd->add_option("--up", o.up, "View-up direction X,Y,Z (default: 0,1,0)");
  cmd->add_option("--fovy", o.fovy, "Vertical view angle in degrees")->capture_default_str();
  cmd->add_option("--background", o.background, "Background colour R,G,B in [0, 1]")->capture_default_str();
  cmd->add_option("--frames", o.frames, "Render this many frames; render_ms is their median")
      ->capture_default_str();
  cmd->add_option("--backend", o.backend, "cpu")->capture_default_str();
  cmd->add_option("-o,--output", o.output, "Output PNG")->required();
  cmd->add_option("--heatmap", o.heatmap, "Write samples per pixel as a colour-coded PNG");
  cmd->add_option("--stats", o.stats, "Write statistics as JSON");
  cmd->callback([options] { runRender(*options); });
}

} // namespace uvr
