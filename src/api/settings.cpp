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

const char *compositingName(Compositing compositing) {
  switch (compositing) {
  case Compositing::Auto:
    return "auto";
  case Compositing::Point:
    return "point";
  case Compositing::Preintegrated:
    return "preintegrated";
  }
  return "?";
}

Compositing parseCompositing(const std::string &name) {
  for (Compositing c : {Compositing::Auto, Compositing::Point, Compositing::Preintegrated})
    if (name == compositingName(c))
      return c;
  throw Error("unknown compositing '" + name + "': expected auto, point or preintegrated");
}

bool preintegrates(Compositing compositing, RenderMode mode) {
  return compositing == Compositing::Preintegrated ||
         (compositing == Compositing::Auto && mode == RenderMode::Full);
}

const char *stepSizingName(StepSizing sizing) {
  switch (sizing) {
  case StepSizing::Auto:
    return "auto";
  case StepSizing::Global:
    return "global";
  case StepSizing::Local:
    return "local";
  }
  return "?";
}

StepSizing parseStepSizing(const std::string &name) {
  for (StepSizing s : {StepSizing::Auto, StepSizing::Global, StepSizing::Local})
    if (name == stepSizingName(s))
      return s;
  throw Error("unknown step sizing '" + name + "': expected auto, global or local");
}

bool stepsFollowMesh(StepSizing sizing, RenderMode mode) {
  return sizing == StepSizing::Local || (sizing == StepSizing::Auto && mode == RenderMode::Full);
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
