#include "front_end.h"

#include <uvr/error.h>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace uvr {

nlohmann::json frameStatsJson(const FrameStats &s) {
  nlohmann::json stats = {
      {"mode", modeName(s.mode)},
      {"compositing", s.preintegrated ? "preintegrated" : "point"},
      {"steps", s.localSteps ? "local" : "global"},
      {"width", s.width},
      {"height", s.height},
      {"cells", s.cells},
      {"partitions", s.partitions},
      {"partitions_skipped", s.partitionsSkipped},
      {"samples_total", s.samplesTotal},
      {"samples_per_pixel_mean", s.samplesPerPixelMean},
      {"samples_per_pixel_max", s.samplesPerPixelMax},
      {"build_ms", s.buildMs},
      {"tf_update_ms", s.tfUpdateMs},
      {"render_ms", s.renderMs},
      {"s1", s.s1},
      {"s2", s.s2},
      {"p", s.p},
      {"unit", s.unit},
      {"leaf_size", s.leafSize},
      {"shaded", s.shaded},
      {"gradient_bytes", s.gradientBytes},
      {"iso_surfaces", s.isoSurfaces},
      {"iso_only", s.isoOnly},
      {"field", s.field},
      {"range", {s.range.min, s.range.max}},
      {"backend", backendName(s.backend)},
      {"threads", s.threads},
      {"host_peak_rss_bytes", s.hostPeakRssBytes},
      {"memory_layout", memoryLayoutName(s.memoryLayout)},
      // One process: `uvr render` under mpirun replaces these with the ranks' (docs/cli.md).
      {"ranks", 1},
      {"rank_render_ms", {s.renderMs}},
      {"composite_ms", 0.0},
      {"composite_bytes", 0},
  };
  if (s.backend == Backend::Cuda) {
    stats["device"] = s.device;
    stats["gpu_memory_bytes"] = s.gpuMemoryBytes;
    stats["gpu_scene_bytes"] = s.gpuSceneBytes;
    stats["gpu_peak_bytes"] = s.gpuPeakBytes;
    nlohmann::json steps = nlohmann::json::object();
    for (const auto &[step, ms] : s.gpuBuildSteps)
      steps[step] = ms;
    stats["gpu_build_steps_ms"] = steps;
  }
  return stats;
}

Backend parseBackendOption(const std::string &name) {
  const Backend backend = parseBackend(name);
  if (!backendAvailable(backend))
    throw Error(
        "this uvr was built without CUDA (no CUDA toolkit was found at build time): use --backend cpu");
  return backend;
}

namespace {

/// A hidden name beside `path` that keeps its extension, which the writers choose the format by.
std::string temporaryPath(const std::string &path) {
  const std::filesystem::path p(path);
  // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) about "." + std::string&&.
  std::string name(1, '.');
  name += p.stem().string();
  name += ".uvr-tmp-";
  name += std::to_string(::getpid());
  name += p.extension().string();
  return (p.parent_path() / name).string();
}

} // namespace

void checkOutputPath(const std::string &path, const std::string &option) {
  if (path.empty())
    throw Error(option + " needs a file name");
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw Error(path, "", option + " names a folder, not a file");
  const std::string probe = temporaryPath(path);
  std::FILE *file = std::fopen(probe.c_str(), "wb");
  if (!file)
    throw Error(path, "", "cannot write " + option + ": " + std::strerror(errno));
  std::fclose(file);
  std::remove(probe.c_str());
}

void writeWhole(const std::string &path, const std::function<void(const std::string &)> &write) {
  const std::string temporary = temporaryPath(path);
  try {
    write(temporary);
  } catch (...) {
    std::remove(temporary.c_str());
    throw;
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const int error = errno;
    std::remove(temporary.c_str());
    throw Error(path, "", std::string("cannot write: ") + std::strerror(error));
  }
}

} // namespace uvr
