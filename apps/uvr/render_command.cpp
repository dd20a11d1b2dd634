#include "commands.h"
#include "render_options.h"

#include "front_end.h"

#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/renderer.h>

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
  FrameSettings settings = parseFrameSettings(o.view);
  if (o.frames < 1)
    throw Error("--frames must be at least 1");

  const LoadedMesh loaded = loadForRendering(o.view);
  const VolumeMesh &mesh = loaded.mesh;

  VolumeRenderer renderer(mesh, loaded.fieldIndex, o.view.leafSize);
  // The acceleration data is built first, outside the frame times (for CUDA on the GPU, so that the transfer
  // function's update is timed where the frames use it).
  renderer.prepare(settings.backend);
  renderer.setTransferFunction(chooseColorMap(o.view.tf, o.view.tfName),
                               transferRange(o.view, mesh, loaded.fieldIndex));
  const Camera camera = chooseCamera(o.view, mesh);
  // The stats take the frame's sample totals; per-pixel counts only the heat map (a copy from a GPU each).
  settings.keepOpacity = false;
  settings.keepSamplesPerPixel = !o.heatmap.empty();

  std::vector<double> times, kernelTimes;
  FrameResult frame;
  for (int i = 0; i < o.frames; ++i) {
    renderer.render(camera, settings, frame);
    times.push_back(frame.stats.renderMs);
    kernelTimes.push_back(frame.stats.gpuKernelMs);
  }
  const auto median = [](std::vector<double> &v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double renderMs = median(times);

  writePng(o.output, frame.image);
  if (!o.heatmap.empty())
    writePng(o.heatmap, heatmapImage(frame.samplesPerPixel, settings.width, settings.height));

  FrameStats &frameStats = frame.stats;
  frameStats.renderMs = renderMs;
  std::fprintf(stderr, "uvr: %s %dx%d, %llu cells, %u partitions, %.1f samples/pixel, %.1f ms/frame\n",
               modeName(settings.mode), settings.width, settings.height,
               static_cast<unsigned long long>(mesh.cellCount()), frameStats.partitions,
               frameStats.samplesPerPixelMean, renderMs);
  if (!o.stats.empty()) {
    nlohmann::json stats = frameStatsJson(frameStats);
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
