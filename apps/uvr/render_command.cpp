#include "commands.h"

#include "core/error.h"
#include "core/timer.h"
#include "image/image.h"
#include "io/mesh_io.h"
#include "mesh/mesh_stats.h"
#include "render/render_defaults.h"
#include "render/renderer.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
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

void writeStats(const std::string &path, const nlohmann::json &stats) {
  std::ofstream out(path);
  out << stats.dump(2) << '\n';
  if (!out)
    throw Error(path, "", "cannot write statistics");
}

void runRender(const RenderOptions &o) {
  int width, height;
  parseSize(o.size, width, height);
  RenderSettings settings;
  settings.backend = parseBackend(o.backend);
  if (o.frames < 1)
    throw Error("--frames must be at least 1");
  const RenderMode mode = parseMode(o.mode);

  const Timer loadTimer;
  const Mesh mesh = loadMesh(o.mesh);
  const double loadMs = loadTimer.milliseconds();
  if (mesh.skippedCells > 0)
    std::fprintf(stderr, "uvr: %s: skipped %llu lower-dimensional cells\n", o.mesh.c_str(),
                 static_cast<unsigned long long>(mesh.skippedCells));
  const int fieldIndex = chooseField(mesh, o.field, o.mesh);

  settings.width = width;
  settings.height = height;
  settings.background = parseVector(o.background, "background");
  settings.integrator = samplingSettings(mode, defaultStepSize(volumeStats(mesh)), o.s1, o.s2, o.p, o.unit);

  Renderer renderer(mesh, fieldIndex, o.leafSize);

  ValueRange range = valueRange(mesh.fields[size_t(fieldIndex)]);
  if (!o.range.empty())
    range = {o.range[0], o.range[1]};
  renderer.setTransferFunction(TransferFunction(chooseColorMap(o.tf, o.tfName), range.min, range.max));

  Camera camera = frameBounds(mesh.bounds(), o.fovy);
  if (!o.at.empty())
    camera.at = parseVector(o.at, "at");
  if (!o.eye.empty())
    camera.eye = parseVector(o.eye, "eye");
  if (!o.up.empty())
    camera.up = parseVector(o.up, "up");
  checkCamera(camera);

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

  nlohmann::json stats =
      frameStats(mesh, renderer, settings, frame, renderMs, o.leafSize, fieldIndex, o.backend);
  std::fprintf(stderr, "uvr: %s %dx%d, %llu cells, %u partitions, %.1f samples/pixel, %.1f ms/frame\n",
               modeName(mode), width, height, static_cast<unsigned long long>(mesh.cellCount()),
               renderer.partitions().count(), stats["samples_per_pixel_mean"].get<double>(), renderMs);
  if (!o.stats.empty()) {
    stats["load_ms"] = loadMs;
    stats["frames"] = o.frames;
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
