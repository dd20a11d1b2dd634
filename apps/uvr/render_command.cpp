#include "commands.h"
#include "movie.h"
#include "render_options.h"

#include "front_end.h"
#include "mpi_group.h"
#include "option_checks.h"
#ifdef UVR_HAS_MPI
#include "data_parallel.h"
#endif

#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/renderer.h>
#include <uvr/system.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>

namespace uvr {

namespace {

struct RenderCommandOptions {
  RenderOptions view;
  MovieOptions movie;
  int frames = 1;
  bool framesGiven = false;
  bool fpsGiven = false;
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

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
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
  if (o.fpsGiven)
    std::fprintf(stderr, "uvr: note: --fps is the frame rate of a movie's video (--time-step A:B, --orbit, "
                         "--camera-path); one image has none\n");

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

#ifdef UVR_HAS_MPI
/// The most memory this process has held (its peak resident set).
uint64_t peakResidentBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return uint64_t(usage.ru_maxrss) * 1024; // kilobytes on Linux
}

/// What the ranks take from the whole mesh: from the mesh read whole, or from a partitioned file's summary.
struct WholeMesh {
  uint64_t cells = 0;
  Box3f bounds;
  float defaultStep = 0.f;
  double medianVolume = 0.0;
  uint32_t leafSize = 0;                     ///< the default
  VolumeMesh::StepScaleReference stepScales; ///< for the leaf size rendered with
  ValueRange fieldRange;
  std::string fieldName;
  MeshRegions regions;
};

/// The partitioned file (`uvr convert --pieces`) whose pieces the ranks read a share each, or none where
/// each reads the mesh whole: not such a file, or its pieces do not fit the ranks (said on stderr).
std::optional<PartitionedFile> piecesForRanks(const RenderOptions &o, int ranks, bool first) {
  std::string extension = std::filesystem::path(o.mesh).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension != ".pvtu")
    return std::nullopt;
  PartitionedFile file = readPartitionedFile(o.mesh);
  const int pieces = int(file.pieces.size());
  const bool powerOf2 = (ranks & (ranks - 1)) == 0;
  std::string why;
  if (file.cells == 0 ||
      std::any_of(file.pieces.begin(), file.pieces.end(), [](const auto &p) { return p.region.empty(); }))
    why = "it was not written by `uvr convert --pieces`";
  else if (pieces != ranks && !(powerOf2 && pieces % ranks == 0))
    why = std::to_string(pieces) + " pieces do not fit " + std::to_string(ranks) +
          " ranks (a rank takes one piece, or where the ranks are a power of 2, as many as each can)";
  else if (o.leafSize != kAutoLeafSize && o.leafSize != file.leafSize)
    why = "it holds the step scales for the default --leaf-size (" + std::to_string(file.leafSize) + ")";
  if (why.empty())
    return file;
  if (first)
    std::fprintf(stderr, "uvr: %s: every rank reads every piece: %s\n", o.mesh.c_str(), why.c_str());
  return std::nullopt;
}

/// Every rank's share of the whole mesh's step scales, on every rank.
std::vector<VolumeMesh::StepScaleShare> gatherShares(MpiGroup &group,
                                                     const VolumeMesh::StepScaleShare &mine) {
  // Each rank's sums, then its counts: one collective.
  std::vector<int64_t> packed(mine.sizeLog2Sums);
  packed.insert(packed.end(), mine.cellCounts.begin(), mine.cellCounts.end());
  std::vector<VolumeMesh::StepScaleShare> shares;
  for (const std::vector<int64_t> &theirs : group.allGather(packed)) {
    const auto half = theirs.begin() + ptrdiff_t(theirs.size() / 2);
    shares.push_back({{theirs.begin(), half}, {half, theirs.end()}});
  }
  return shares;
}

/// This rank's share of a partitioned file: its consecutive pieces with their ghost cells, field
/// `fieldIndex` alone (chosen by --field), as one mesh.
VolumeMesh readShare(const RenderOptions &o, const PartitionedFile &file, int rank, int ranks,
                     FieldInfo &field) {
  const size_t each = file.pieces.size() / size_t(ranks);
  std::vector<Box3f> owned;
  for (size_t i = 0; i < each; ++i)
    owned.push_back(file.pieces[size_t(rank) * each + i].region);
  std::vector<VolumeMesh> parts;
  int fieldIndex = -1;
  const auto withField = [&](VolumeMesh mesh) {
    if (fieldIndex < 0) {
      try {
        fieldIndex = mesh.chooseField(o.field);
      } catch (const Error &e) {
        throw Error(std::string(e.what()) + (o.field.empty() ? "" : " (--field)"));
      }
      field = mesh.field(fieldIndex);
    }
    return std::move(mesh).withFields({fieldIndex});
  };
  for (size_t i = 0; i < each; ++i) {
    const PartitionedFile::Piece &piece = file.pieces[size_t(rank) * each + i];
    parts.push_back(withField(VolumeMesh::load(piece.path)));
    if (!piece.ghosts.empty()) {
      const VolumeMesh ghosts = withField(VolumeMesh::load(piece.ghosts));
      // Those owned by another of this rank's pieces, or in an earlier one's ghosts, are here already.
      parts.push_back(
          each == 1 ? ghosts
                    : ghostCellsOutside(ghosts, owned,
                                        std::vector<Box3f>(owned.begin(), owned.begin() + ptrdiff_t(i))));
    }
  }
  return mergeMeshes(parts, o.mesh);
}

/// `uvr render` over the ranks of an MPI run: each rank draws the cells of its region of a KD split of the
/// mesh, the ranks composite their premultiplied images in visibility order, and rank 0 applies the
/// background and writes the outputs. Each rank reads its share of a partitioned file (piecesForRanks), and
/// the mesh whole otherwise.
void runRenderParallel(const RenderCommandOptions &o) {
  MpiGroup group;
  const bool first = group.rank() == 0;
  // The ranks on a node share its cores: each takes its share, as a launcher that binds them gives it.
  setThreadCount(
      std::min(threadCount(), std::max(1, int(std::thread::hardware_concurrency()) / group.nodeSize())));
  FrameSettings settings;
  ColorMap colorMap;
  group.step([&] {
    settings = parseFrameSettings(o.view);
    if (o.frames < 1)
      throw Error("--frames must be at least 1");
    if (isMovie(o.view, o.movie))
      throw Error("movies (a range of time steps, --orbit, --camera-path) are rendered by one process; run "
                  "it without mpirun");
    if (first)
      checkOutputs(o);
    colorMap = chooseTransferFunction(o.view);
  });

  // This rank's cells (field 0 alone), and what depends on the whole mesh: defaults, value range, camera,
  // leaf size, the split.
  WholeMesh whole;
  std::optional<VolumeMesh> part;
  double loadMs = 0.0;     ///< until this rank holds its cells and what it takes from the whole mesh
  double fileLoadMs = 0.0; ///< the file's read alone, where read whole (load_ms, as before)
  std::optional<PartitionedFile> partitioned;
  group.step([&] { partitioned = piecesForRanks(o.view, group.size(), first); });
  uint64_t loadPeakBytes = 0;
  if (partitioned) {
    group.step([&] {
      const Timer loadTimer;
      FieldInfo field;
      part.emplace(readShare(o.view, *partitioned, group.rank(), group.size(), field));
      whole.fieldName = field.name;
      loadMs = fileLoadMs = loadTimer.milliseconds();
      const PartitionedFile &file = *partitioned;
      whole.cells = file.cells;
      whole.bounds = file.bounds;
      whole.defaultStep = file.defaultStep;
      whole.medianVolume = file.medianVolume;
      whole.leafSize = file.leafSize;
      whole.stepScales = file.stepScales;
      const auto range = std::find_if(file.fieldRanges.begin(), file.fieldRanges.end(), [&](const auto &f) {
        return f.field.name == field.name && f.field.centering == field.centering;
      });
      if (range == file.fieldRanges.end() && o.view.range.empty())
        throw Error(o.view.mesh, "", "no range of field '" + whole.fieldName + "' in the file: give --range");
      if (range != file.fieldRanges.end())
        whole.fieldRange = range->range;
      std::vector<Box3f> pieceRegions;
      for (const PartitionedFile::Piece &piece : file.pieces)
        pieceRegions.push_back(piece.region);
      whole.regions = regionsOfPieces(pieceRegions, group.size());
    });
  } else {
    std::optional<LoadedMesh> loaded;
    group.step([&] { loaded.emplace(loadForRendering(o.view)); });
    VolumeMesh::StepScaleShare share;
    group.step([&] {
      const Timer pieceTimer; // the load ends with this rank's piece, as a share's does
      const VolumeMesh &mesh = loaded->mesh;
      whole.cells = mesh.cellCount();
      whole.bounds = mesh.bounds();
      if (whole.cells < uint64_t(group.size()))
        throw Error(mesh.source(), "", "fewer cells than ranks: run fewer ranks");
      whole.medianVolume = mesh.volumeStats().median;
      whole.defaultStep = mesh.defaultStep();
      whole.leafSize = mesh.defaultLeafSize();
      whole.fieldRange = mesh.fieldRange(loaded->fieldIndex);
      whole.fieldName = mesh.field(loaded->fieldIndex).name;
      whole.regions = splitIntoRegions(mesh, group.size());
      const Box3f &region = whole.regions.regions[size_t(group.rank())];
      part.emplace(meshPiece(mesh, loaded->fieldIndex, region));
      fileLoadMs = loaded->loadMs;
      loaded.reset(); // the piece is all this rank keeps: gone before the partitions below are built
      // Each rank's partitions within its region, not the whole mesh's on every rank.
      share = part->stepScaleShare(region, whole.bounds,
                                   o.view.leafSize != kAutoLeafSize ? o.view.leafSize : whole.leafSize);
      loadMs = fileLoadMs + pieceTimer.milliseconds();
    });
    whole.stepScales = VolumeMesh::stepScaleReference(gatherShares(group, share));
  }

  loadPeakBytes = peakResidentBytes();

  std::optional<VolumeRenderer> renderer;
  Camera camera;
  const MeshRegions &regions = whole.regions;
  group.step([&] {
    const bool defaults =
        !(settings.s1 > 0.f && settings.s2 > 0.f && settings.p > 0.f && settings.unit > 0.f);
    if (defaults && !(settings.s1 > 0.f && settings.unit > 0.f) && !(whole.medianVolume > 0.0))
      throw Error(o.view.mesh, "", "no default step: the median cell volume is 0; give --s1 and --unit");
    if (defaults)
      settings =
          withDefaultSampling(settings, whole.defaultStep, defaultUnitDistance(whole.bounds, whole.cells));
    validateSettings(settings);
    const ValueRange range = transferRange(o.view, whole.fieldRange, whole.fieldName);
    camera = chooseCamera(o.view, whole.bounds);
    const uint32_t leafSize = o.view.leafSize != kAutoLeafSize ? o.view.leafSize : whole.leafSize;
    const MeshPiece piece{regions.regions[size_t(group.rank())], whole.bounds, whole.stepScales};
    if (settings.backend == Backend::Cuda)
      setCudaDevice(group.localRank() % std::max(1, cudaDeviceCount()));
    renderer.emplace(std::move(*part), 0, leafSize, piece);
    part.reset();
    renderer->prepare(settings.backend);
    renderer->setTransferFunction(colorMap, range);
  });
  // Adaptive steps normalise each partition's colour deviation by the extremes over all partitions: the
  // whole mesh's, over every rank's.
  ValueRange variances;
  group.step([&] { variances = renderer->colorVarianceRange(settings.backend); });
  variances = {float(-group.maxOf(-double(variances.min))), float(group.maxOf(variances.max))};
  group.step([&] { renderer->setColorVarianceRange(variances); });

  // What the composite takes, and no more: a GPU copies each buffer kept back to the host.
  settings.keepImage = false;
  settings.keepOpacity = false;
  settings.keepSamplesPerPixel = !o.heatmap.empty();
  settings.keepPremultipliedRgba16 = true;
  const std::vector<int> order = regions.frontToBack(camera.eye);
  const PixelBox colour =
      boxPixels(camera, settings.width, settings.height, regions.regions[size_t(group.rank())]);
  std::vector<double> frameTimes, rankTimes, rankKernelTimes, compositeTimes;
  FrameResult frame;
  Image image; // the composited frame, on rank 0
  double tfUpdateMs = 0.0;
  uint64_t sentBytes = 0;
  for (int i = 0; i < o.frames; ++i) {
    group.barrier();
    const Timer frameTimer;
    group.step([&] { renderer->render(camera, settings, frame); });
    if (i == 0)
      tfUpdateMs = frame.stats.tfUpdateMs;
    rankTimes.push_back(frame.stats.renderMs);
    rankKernelTimes.push_back(frame.stats.gpuKernelMs);
    group.barrier(); // the composite's time, not the wait for the slowest rank's render
    const Timer compositeTimer;
    sentBytes = group.composite(frame.premultipliedRgba16, settings.width, settings.height, order, colour,
                                settings.background, image);
    compositeTimes.push_back(compositeTimer.milliseconds());
    frameTimes.push_back(frameTimer.milliseconds());
  }

  // Every rank takes part in the sums; rank 0 reports them.
  FrameStats stats = frame.stats;
  const std::vector<double> rankRenderMs = group.gather(median(rankTimes));
  const std::vector<double> rankKernelMs = group.gather(median(rankKernelTimes));
  const std::vector<double> rankSamples = group.gather(double(stats.samplesTotal));
  const double compositeMs = group.maxOf(median(compositeTimes));
  const double frameMs = group.maxOf(median(frameTimes));
  const uint64_t compositeBytes = group.sumOf(sentBytes);
  const double slowestLoadMs = group.maxOf(fileLoadMs);
  const std::vector<double> rankLoadMs = group.gather(loadMs);
  const std::vector<double> rankPeakBytes = group.gather(double(peakResidentBytes()));
  const std::vector<double> rankLoadPeakBytes = group.gather(double(loadPeakBytes));
  const std::vector<double> rankGpuPeakBytes = group.gather(double(frame.stats.gpuPeakBytes));
  stats.samplesTotal = group.sumOf(stats.samplesTotal);
  stats.partitions = uint32_t(group.sumOf(stats.partitions));
  stats.partitionsSkipped = uint32_t(group.sumOf(stats.partitionsSkipped));
  stats.buildMs = group.maxOf(stats.buildMs);
  tfUpdateMs = group.maxOf(tfUpdateMs);
  std::vector<uint32_t> samplesPerPixel;
  if (settings.keepSamplesPerPixel) {
    samplesPerPixel = group.sum(frame.samplesPerPixel);
    stats.samplesPerPixelMax = first ? *std::max_element(samplesPerPixel.begin(), samplesPerPixel.end()) : 0;
  } else {
    // Without the per-pixel counts, the most any rank's part of a pixel took.
    stats.samplesPerPixelMax = uint32_t(group.maxOf(stats.samplesPerPixelMax));
  }
  stats.cells = whole.cells;
  stats.samplesPerPixelMean = double(stats.samplesTotal) / (double(settings.width) * double(settings.height));
  stats.renderMs = frameMs;
  stats.tfUpdateMs = tfUpdateMs;
  const int ranks = group.size();

  group.step([&] {
    if (!first)
      return;
    std::fprintf(stderr,
                 "uvr: %s %dx%d, %llu cells, %d ranks, %u partitions, %.1f samples/pixel, %.1f ms/frame "
                 "(composite %.1f ms)\n",
                 modeName(settings.mode), settings.width, settings.height,
                 static_cast<unsigned long long>(whole.cells), ranks, stats.partitions,
                 stats.samplesPerPixelMean, frameMs, compositeMs);
    if (!o.stats.empty()) {
      nlohmann::json json = frameStatsJson(stats);
      json["load_ms"] = slowestLoadMs;
      json["time_step"] = o.view.timeStep;
      json["frames"] = o.frames;
      json["ranks"] = ranks;
      json["rank_render_ms"] = rankRenderMs;
      json["rank_samples"] = rankSamples; // with rank_render_ms, the load balance
      if (settings.backend == Backend::Cuda)
        json["rank_gpu_kernel_ms"] = rankKernelMs;
      json["composite_ms"] = compositeMs;
      json["composite_bytes"] = compositeBytes;
      json["rank_load_ms"] = rankLoadMs;
      // Peak resident memory per rank, in all and up to the end of the load (its share of the mesh read).
      const auto bytes = [](const std::vector<double> &values) {
        return std::vector<uint64_t>(values.begin(), values.end());
      };
      json["rank_peak_rss_bytes"] = bytes(rankPeakBytes);
      json["rank_load_peak_rss_bytes"] = bytes(rankLoadPeakBytes);
      if (settings.backend == Backend::Cuda)
        json["rank_gpu_peak_bytes"] = bytes(rankGpuPeakBytes);
      // Each rank's region within the mesh's bounds: where the split planes lie.
      nlohmann::json boxes = nlohmann::json::array();
      for (const Box3f &region : regions.regions) {
        const Box3f box = {vmax(region.lower, whole.bounds.lower), vmin(region.upper, whole.bounds.upper)};
        boxes.push_back({box.lower.x, box.lower.y, box.lower.z, box.upper.x, box.upper.y, box.upper.z});
      }
      json["rank_regions"] = boxes;
      writeStats(o.stats, json);
    }
    if (!o.heatmap.empty()) {
      const Image heatmap = heatmapImage(samplesPerPixel, settings.width, settings.height);
      writeWhole(o.heatmap, [&](const std::string &temporary) { writePng(temporary, heatmap); });
    }
    writeWhole(o.output, [&](const std::string &temporary) { writePng(temporary, image); });
  });
}
#endif

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
    options->fpsGiven = cmd->count("--fps") > 0;
    if (!startedByMpiLauncher())
      return runRender(*options);
#ifdef UVR_HAS_MPI
    runRenderParallel(*options);
#else
    throw Error("started by an MPI launcher, but this uvr was built without MPI (UVR_MPI); run it alone");
#endif
  });
}

} // namespace uvr
