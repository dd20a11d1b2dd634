#include "commands.h"
#include "render_options.h"

#include "core/error.h"
#include "core/timer.h"
#include "engine/render_defaults.h"
#include "engine/renderer.h"
#include "image/image.h"
#include "io/color_map_io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>

namespace uvr {

namespace {

struct RenderCommandOptions {
  RenderOptions view;
  int frames = 1;
  std::string output;
  std::string heatmap;
  std::string stats;
};

void writeStats(const std::string &path, const nlohmann::json &stats) {
  std::ofstream out(path);
  out << stats.dump(2) << '\n';
  if (!out)
    throw Error(path, "", "cannot write statistics");
}

void runRender(const RenderCommandOptions &o) {
  RenderSettings settings = parseRenderSettings(o.view);
  if (o.frames < 1)
    throw Error("--frames must be at least 1");

  const LoadedMesh loaded = loadForRendering(o.view);
  const Mesh &mesh = loaded.mesh;
  settings.integrator = chooseSampling(o.view, mesh);

  Renderer renderer(mesh, loaded.fieldIndex, o.view.leafSize);
  // The acceleration data is built first, outside the frame times (for CUDA on the GPU, so that the transfer
  // function's update is timed where the frames use it).
  renderer.prepare(settings.backend);
  const ValueRange range = transferRange(o.view, mesh.fields[size_t(loaded.fieldIndex)]);
  renderer.setTransferFunction(
      TransferFunction(chooseColorMap(o.view.tf, o.view.tfName), range.min, range.max));
  const Camera camera = chooseCamera(o.view, mesh);
  // The stats take the frame's sample totals; per-pixel counts only the heat map (a copy from a GPU each).
  settings.keepOpacity = false;
  settings.keepSamplesPerPixel = !o.heatmap.empty();

  std::vector<double> times, kernelTimes;
  Frame frame;
  for (int i = 0; i < o.frames; ++i) {
    const Timer timer;
    renderer.render(camera, settings, frame);
    times.push_back(timer.milliseconds());
    kernelTimes.push_back(frame.kernelMs);
  }
  const auto median = [](std::vector<double> &v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double renderMs = median(times);

  writePng(o.output, frame.image);
  if (!o.heatmap.empty())
    writePng(o.heatmap, heatmapImage(frame.samplesPerPixel, settings.width, settings.height));

  nlohmann::json stats = frameStats(mesh, renderer, settings, frame, renderMs, loaded.fieldIndex);
  std::fprintf(stderr, "uvr: %s %dx%d, %llu cells, %u partitions, %.1f samples/pixel, %.1f ms/frame\n",
               modeName(settings.integrator.mode), settings.width, settings.height,
               static_cast<unsigned long long>(mesh.cellCount()), renderer.partitionCount(settings.backend),
               stats["samples_per_pixel_mean"].get<double>(), renderMs);
  if (!o.stats.empty()) {
    stats["load_ms"] = loaded.loadMs;
    stats["time_step"] = o.view.timeStep;
    stats["frames"] = o.frames;
    if (settings.backend == Backend::Cuda)
      stats["gpu_kernel_ms"] = median(kernelTimes);
    writeStats(o.stats, stats);
  }
}

} // namespace

void addRenderCommand(CLI::App &app) {
  auto options = std::make_shared<RenderCommandOptions>();
  RenderCommandOptions &o = *options;
  CLI::App *cmd = app.add_subcommand("render", "Render a mesh to a PNG");
  addRenderOptions(cmd, o.view);
  cmd->add_option("--frames", o.frames, "Render this many frames; render_ms is their median")
      ->capture_default_str();
  cmd->add_option("-o,--output", o.output, "Output PNG")->required();
  cmd->add_option("--heatmap", o.heatmap, "Write samples per pixel as a colour-coded PNG");
  cmd->add_option("--stats", o.stats, "Write statistics as JSON");
  cmd->callback([options] { runRender(*options); });
}

} // namespace uvr
