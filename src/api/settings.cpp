#include <uvr/error.h>
#ifdef UVR_HAVE_CUDA
#include "backend/cuda/cuda_backend.h"
#include "render/isosurface.h"
#endif

#include <uvr/settings.h>
#include <uvr/system.h>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

namespace uvr {

namespace {

/// Defaults chosen by measurement (docs/design.md, "Choosing defaults"): s2 = kDefaultS2Factor * s1.
constexpr float kDefaultS2Factor = 8.f;
constexpr float kDefaultP = 4.f;

/// Names of each enumeration's values, in the order of its values.
constexpr const char *kModeNames[] = {"reference", "skip", "adaptive", "full"};
constexpr const char *kCompositingNames[] = {"auto", "point", "preintegrated"};
constexpr const char *kStepSizingNames[] = {"auto", "global", "local"};

template <typename Enum, size_t N> const char *nameOf(Enum value, const char *const (&names)[N]) {
  return size_t(value) < N ? names[size_t(value)] : "?";
}

/// The value named `name`; else an error naming `what` and listing the names.
template <typename Enum, size_t N>
Enum parseName(const std::string &name, const char *const (&names)[N], const char *what) {
  std::string expected;
  for (size_t i = 0; i < N; ++i) {
    if (name == names[i])
      return Enum(i);
    expected += std::string(i == 0 ? "" : i + 1 == N ? " or " : ", ") + names[i];
  }
  throw Error("unknown " + std::string(what) + " '" + name + "': expected " + expected);
}

} // namespace

const char *modeName(RenderMode mode) { return nameOf(mode, kModeNames); }
RenderMode parseMode(const std::string &name) { return parseName<RenderMode>(name, kModeNames, "mode"); }

const char *compositingName(Compositing compositing) { return nameOf(compositing, kCompositingNames); }
Compositing parseCompositing(const std::string &name) {
  return parseName<Compositing>(name, kCompositingNames, "compositing");
}

bool preintegrates(Compositing compositing, RenderMode mode) {
  return compositing == Compositing::Preintegrated ||
         (compositing == Compositing::Auto && mode == RenderMode::Full);
}

const char *stepSizingName(StepSizing sizing) { return nameOf(sizing, kStepSizingNames); }
StepSizing parseStepSizing(const std::string &name) {
  return parseName<StepSizing>(name, kStepSizingNames, "steps");
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

const char *memoryLayoutName(MemoryLayout layout) {
  switch (layout) {
  case MemoryLayout::Default:
    return "default";
  case MemoryLayout::Lean:
    return "lean";
  default:
    return "auto";
  }
}

MemoryLayout parseMemoryLayout(const std::string &name) {
  if (name == "auto")
    return MemoryLayout::Auto;
  if (name == "default")
    return MemoryLayout::Default;
  if (name == "lean")
    return MemoryLayout::Lean;
  throw Error("unknown memory layout '" + name + "': expected auto, default or lean");
}

namespace {
std::atomic<MemoryLayout> layoutSetting{MemoryLayout::Auto};
} // namespace

void setMemoryLayout(MemoryLayout layout) { layoutSetting = layout; }
MemoryLayout memoryLayout() { return layoutSetting; }

bool backendAvailable(Backend backend) {
#ifdef UVR_HAVE_CUDA
  return backend == Backend::Cpu || backend == Backend::Cuda;
#else
  return backend == Backend::Cpu;
#endif
}

FrameSettings withDefaultSampling(FrameSettings settings, float defaultStep) {
  return withDefaultSampling(settings, defaultStep, defaultStep);
}

FrameSettings withDefaultSampling(FrameSettings settings, float defaultStep, float defaultUnit) {
  settings.s1 = settings.s1 > 0.f ? settings.s1 : defaultStep;
  settings.s2 = settings.s2 > 0.f ? settings.s2 : std::max(kDefaultS2Factor * defaultStep, settings.s1);
  settings.p = settings.p > 0.f ? settings.p : kDefaultP;
  settings.unit = settings.unit > 0.f ? settings.unit : defaultUnit;
  return settings;
}

float defaultUnitDistance(const Box3f &bounds, uint64_t cells) {
  // vtkSMRepresentationProxy's default ScalarOpacityUnitDistance: diagonal / cbrt(cells).
  if (cells == 0 || bounds.empty())
    return 1.f;
  const double diagonal = double(length(bounds.size()));
  const double unit = diagonal / std::cbrt(double(cells));
  return unit > 0.0 && std::isfinite(unit) ? float(unit) : 1.f;
}

void validateSettings(const FrameSettings &s) {
  const auto check = [](float value, const char *name) {
    if (!(value >= 0.f) || !std::isfinite(value))
      throw Error(std::string(name) + " must be a positive finite number (0: the default); got " +
                  std::to_string(value));
  };
  check(s.s1, "s1");
  check(s.s2, "s2");
  check(s.p, "p");
  check(s.unit, "unit");
  if (s.p > 0.f && s.p < 1.f)
    throw Error("p must be at least 1; got " + std::to_string(s.p));
  if (s.s1 > 0.f && s.s2 > 0.f && s.s2 < s.s1)
    throw Error("s2 (" + std::to_string(s.s2) + ") must be at least s1 (" + std::to_string(s.s1) + ")");
  if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384)
    throw Error("the image size must be 1 to 16384 pixels a side; got " + std::to_string(s.width) + "x" +
                std::to_string(s.height));
  for (const float c : {s.background.x, s.background.y, s.background.z})
    if (!(c >= 0.f && c <= 1.f))
      throw Error("background components must be in [0, 1]; got " + std::to_string(s.background.x) + "," +
                  std::to_string(s.background.y) + "," + std::to_string(s.background.z));
  if (!s.rayLimits.empty()) {
    if (s.rayLimits.size() != size_t(s.width) * size_t(s.height))
      throw Error("rayLimits must hold one distance per pixel (" + std::to_string(s.width) + "x" +
                  std::to_string(s.height) + "); got " + std::to_string(s.rayLimits.size()));
    for (const float limit : s.rayLimits)
      if (!(limit >= 0.f))
        throw Error("rayLimits must be non-negative distances or +inf; got " + std::to_string(limit));
  }
  if (!std::isfinite(s.light.x) || !std::isfinite(s.light.y) || !std::isfinite(s.light.z))
    throw Error("the light direction must be finite");
  for (const auto &[value, name] :
       {std::pair{s.ambient, "ambient"}, std::pair{s.diffuse, "diffuse"}, std::pair{s.specular, "specular"}})
    if (!(value >= 0.f) || !std::isfinite(value))
      throw Error(std::string(name) + " must be a finite number >= 0; got " + std::to_string(value));
  if (!(s.shininess >= 1.f) || !std::isfinite(s.shininess))
    throw Error("shininess must be a finite number >= 1; got " + std::to_string(s.shininess));
  if (s.isoValues.size() > kMaxIsoSurfaces)
    throw Error("at most " + std::to_string(kMaxIsoSurfaces) + " isosurface values; got " +
                std::to_string(s.isoValues.size()));
  for (const float value : s.isoValues)
    if (!std::isfinite(value))
      throw Error("isosurface values must be finite; got " + std::to_string(value));
  if (s.isoColor)
    for (const float c : {s.isoColor->x, s.isoColor->y, s.isoColor->z})
      if (!(c >= 0.f && c <= 1.f))
        throw Error("isosurface colour components must be in [0, 1]; got " + std::to_string(s.isoColor->x) +
                    "," + std::to_string(s.isoColor->y) + "," + std::to_string(s.isoColor->z));
  if (!(s.isoOpacity > 0.f && s.isoOpacity <= 1.f))
    throw Error("isosurface opacity must be in (0, 1]; got " + std::to_string(s.isoOpacity));
  if (s.isoOnly && s.isoValues.empty())
    throw Error("isoOnly needs isosurface values to draw");
}

namespace {
std::mutex threadLimitMutex;
std::unique_ptr<tbb::global_control> threadLimit;
} // namespace

int threadCount() {
  const std::lock_guard lock(threadLimitMutex);
  const int all = tbb::info::default_concurrency();
  return threadLimit
             ? std::min(all,
                        int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)))
             : all;
}

void setThreadCount(int threads) {
  if (threads < 0)
    throw Error("a thread count must not be negative; got " + std::to_string(threads));
  const std::lock_guard lock(threadLimitMutex);
  threadLimit.reset();
  if (threads > 0)
    threadLimit =
        std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
}

uint64_t hostPeakRssBytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0)
    return 0;
  return uint64_t(usage.ru_maxrss) * 1024; // kilobytes on Linux
}

int cudaDeviceCount() {
#ifdef UVR_HAVE_CUDA
  return cudaDevicesVisible();
#else
  return 0;
#endif
}

void setCudaDevice(int ordinal) {
  if (ordinal < 0)
    throw Error("a CUDA device ordinal must not be negative; got " + std::to_string(ordinal));
#ifdef UVR_HAVE_CUDA
  selectCudaDevice(ordinal);
#endif
}

} // namespace uvr
