#include "commands.h"
#include "movie.h"
#include "render_options.h"

#include "front_end.h"
#include "option_checks.h"

#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/renderer.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

namespace uvr {

namespace {

struct RenderCommandOptions {
  RenderOptions view;
  MovieOptions movie;
  int frames = 1;
  bool framesGiven = false;
  std::string output;
  std::string heatmap;
  std::string stats;
};

void writeStats(const std::string &path, const nlohmann::json &stats) {
  writeWhole(path, [&](const std::string &temporary) {
    std::ofstream out(temporary);
    out << stats.dump(2) << '\n';
    out.close();
    if (!out)
      throw Error(path, "", std::string("cannot write statistics: ") + std::strerror(errno));
  });
}

bool endsWithPng(const std::string &path) {
  std::string tail = path.size() >= 4 ? path.substr(path.size() - 4) : path;
  std::transform(tail.begin(), tail.end(), tail.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return tail == ".png";
}

/// Every output is checked before the mesh is loaded: a bad name or folder costs nothing.
void checkOutputs(const RenderCommandOptions &o) {
  for (const auto &[path, option] : {std::pair{&o.output, "-o"}, std::pair{&o.heatmap, "--heatmap"}}) {
    if (option == std::string("--heatmap") && path->empty())
      continue;
    if (!endsWithPng(*path))
      throw Error(*path, "", std::string(option) + " writes PNG images only: give a name ending in .png");
    checkOutputPath(*path, option);
  }
  if (!o.stats.empty())
    checkOutputPath(o.stats, "--stats");
}

void runRender(const RenderCommandOptions &o) {
  FrameSettings settings = parseFrameSettings(o.view);
  if (o.frames < 1)
    throw Error("--frames must be at least 1");
  checkOutputs(o);
  const ColorMap colorMap = chooseTransferFunction(o.view);
  if (isMovie(o.view, o.movie)) {
    renderMovie(o.view, o.movie, settings, colorMap,
                {o.output, o.heatmap, o.stats, o.framesGiven ? std::optional<int>(o.frames) : std::nullopt});
    return;
  }

  const LoadedMesh loaded = loadForRendering(o.view);
  const VolumeMesh &mesh = loaded.mesh;

  warnOfSmallStep(settings, mesh);

  VolumeRenderer renderer(mesh, loaded.fieldIndex, o.view.leafSize);
  // The acceleration data is built first, outside the frame times (for CUDA on the GPU, so that the transfer
  // function's update is timed where the frames use it).
  renderer.prepare(settings.backend);
  renderer.setTransferFunction(colorMap, transferRange(o.view, mesh, loaded.fieldIndex));
  const Camera camera = chooseCamera(o.view, mesh);
  // The stats take the frame's sample totals; per-pixel counts only the heat map (a copy from a GPU each).
  settings.keepOpacity = false;
  settings.keepSamplesPerPixel = !o.heatmap.empty();

  std::vector<double> times, kernelTimes;
  FrameResult frame;
  double tfUpdateMs = 0.0; // the first frame's: the later ones waited for no update
  for (int i = 0; i < o.frames; ++i) {
    renderer.render(camera, settings, frame);
    if (i == 0)
      tfUpdateMs = frame.stats.tfUpdateMs;
    times.push_back(frame.stats.renderMs);
    kernelTimes.push_back(frame.stats.gpuKernelMs);
  }
  const auto median = [](std::vector<double> &v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double renderMs = median(times);

  // Statistics first: a PNG is never left behind by a failure after it.
  FrameStats &frameStats = frame.stats;
  frameStats.renderMs = renderMs;
  frameStats.tfUpdateMs = tfUpdateMs;
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
  if (!o.heatmap.empty()) {
    const Image heatmap = heatmapImage(frame.samplesPerPixel, settings.width, settings.height);
    writeWhole(o.heatmap, [&](const std::string &temporary) { writePng(temporary, heatmap); });
  }
  writeWhole(o.output, [&](const std::string &temporary) { writePng(temporary, frame.image); });
}

} // namespace

void addRenderCommand(CLI::App &app) {
  auto options = std::make_shared<RenderCommandOptions>();
  RenderCommandOptions &o = *options;
  CLI::App *cmd = app.add_subcommand("render", "Render a mesh to a PNG");
  addRenderOptions(cmd, o.view, /*timeRanges=*/true);
  addMovieOptions(cmd, o.movie);
  cmd->add_option("--frames", o.frames,
                  "Render this many frames; render_ms is their median (of a movie: its frame count)")
      ->check(integerAtLeast(1))
      ->capture_default_str();
  cmd->add_option("-o,--output", o.output, "Output PNG (.png)")->required();
  cmd->add_option("--heatmap", o.heatmap, "Write samples per pixel as a colour-coded PNG");
  cmd->add_option("--stats", o.stats, "Write statistics as JSON");
  cmd->callback([options, cmd] {
    options->framesGiven = cmd->count("--frames") > 0;
    runRender(*options);
  });
}

} // namespace uvr
