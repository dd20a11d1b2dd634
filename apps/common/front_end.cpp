#include "front_end.h"

#include <uvr/error.h>

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
      {"field", s.field},
      {"range", {s.range.min, s.range.max}},
      {"backend", backendName(s.backend)},
      {"threads", s.threads},
  };
  if (s.backend == Backend::Cuda) {
    stats["device"] = s.device;
    stats["gpu_memory_bytes"] = s.gpuMemoryBytes;
    stats["gpu_scene_bytes"] = s.gpuSceneBytes;
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

void checkCamera(const Camera &camera) {
  if (length(cross(camera.at - camera.eye, camera.up)) == 0.f)
    throw Error("--eye, --at and --up must not be collinear");
}

} // namespace uvr
