#include <uvr/error.h>

#include <uvr/settings.h>
#include <uvr/system.h>

#include <tbb/info.h>

#include <algorithm>

namespace uvr {

namespace {

/// Defaults chosen by measurement (docs/design.md, "Choosing defaults"): s2 = kDefaultS2Factor * s1.
constexpr float kDefaultS2Factor = 8.f;
constexpr float kDefaultP = 4.f;

} // namespace

const char *modeName(RenderMode mode) {
  switch (mode) {
  case RenderMode::Reference:
    return "reference";
  case RenderMode::Skip:
    return "skip";
  case RenderMode::Adaptive:
    return "adaptive";
  case RenderMode::Full:
    return "full";
  }
  return "?";
}

RenderMode parseMode(const std::string &name) {
  for (RenderMode mode : {RenderMode::Reference, RenderMode::Skip, RenderMode::Adaptive, RenderMode::Full})
    if (name == modeName(mode))
      return mode;
  throw Error("unknown mode '" + name + "': expected reference, skip, adaptive or full");
}

const char *backendName(Backend backend) { return backend == Backend::Cuda ? "cuda" : "cpu"; }

Backend parseBackend(const std::string &name) {
  if (name == "cpu")
    return Backend::Cpu;
  if (name == "cuda")
    return Backend::Cuda;
  throw Error("unknown backend '" + name + "': expected cpu or cuda");
}

bool backendAvailable(Backend backend) {
#ifdef UVR_HAVE_CUDA
  return backend == Backend::Cpu || backend == Backend::Cuda;
#else
  return backend == Backend::Cpu;
#endif
}

FrameSettings withDefaultSampling(FrameSettings settings, float defaultStep) {
  settings.s1 = settings.s1 > 0.f ? settings.s1 : defaultStep;
  settings.s2 = settings.s2 > 0.f ? settings.s2 : std::max(kDefaultS2Factor * defaultStep, settings.s1);
  settings.p = settings.p > 0.f ? settings.p : kDefaultP;
  settings.unit = settings.unit > 0.f ? settings.unit : defaultStep;
  return settings;
}

int threadCount() { return tbb::info::default_concurrency(); }

} // namespace uvr
