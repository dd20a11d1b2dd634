#include "engine/renderer.h"
#include "api/access.h"
#include "core/limits.h"
#include <uvr/error.h>

#include <uvr/renderer.h>
#include <uvr/system.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <optional>
#include <span>
#include <sstream>

namespace uvr {

namespace {

bool sameColorMap(const ColorMap &a, const ColorMap &b) {
  return a.rgbPoints == b.rgbPoints && a.opacityPoints == b.opacityPoints && a.colorSpace == b.colorSpace &&
         a.nanColor.x == b.nanColor.x && a.nanColor.y == b.nanColor.y && a.nanColor.z == b.nanColor.z;
}

std::string numberText(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

/// What a frame may allocate per pixel, for the memory limit: the library's colour, opacity and sample
/// buffers, and the copies the front ends make of them (RGBA, PNG rows, heat map).
constexpr uint64_t kFrameBytesPerPixel = 32;

template <typename T> bool sameArray(std::span<const T> a, std::span<const T> b) {
  return a.size() == b.size() &&
         (a.data() == b.data() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

/// Whether `a` and `b` hold the same points and cells, bit for bit, in the same order.
bool sameGrid(const VolumeMesh &a, const VolumeMesh &b) {
  if (!sameArray(a.points(), b.points()))
    return false;
  for (CellType type : {CellType::Tetra, CellType::Pyramid, CellType::Wedge, CellType::Hexahedron})
    if (!sameArray(a.cells(type), b.cells(type)))
      return false;
  return true;
}

} // namespace

ValueRange defaultTransferRange(ValueRange r) {
  if (r.min < r.max)
    return r;
  const float half = 0.5f * std::max(1.f, std::fabs(r.min) * 1e-3f);
  return {r.min - half, r.min + half};
}

struct VolumeRenderer::Impl {
  VolumeMesh mesh; // keeps the data the renderer refers to
  int fieldIndex;
  Renderer renderer;
  std::optional<ColorMap> map; // the transfer function set last, and its range
  ValueRange range;
  // What the next frame reports as tf_update_ms: the metadata update since the last frame, timed where a
  // backend did it (a function set before any backend is timed when the backend takes it in prepare).
  double tfUpdateMs = 0.0;
  bool tfTimed = false;   // tfUpdateMs holds an update on a backend
  bool tfPending = false; // set, but no backend has taken it yet
  // Serialises building, transfer-function changes and frames: the backends are made lazily and the
  // partitions' metadata is replaced in place, so neither may race a frame.
  std::mutex mutex;

  /// VolumeRenderer::prepare, with the mutex held.
  void prepare(Backend backend) {
    if (renderer.prepared(backend))
      return;
    renderer.prepare(backend);
    if (tfPending && map) {
      // The new backend took the function in its build; time its update alone, as a change would be timed.
      const Timer timer;
      renderer.setTransferFunction(TransferFunction(*map, range.min, range.max));
      tfUpdateMs = timer.milliseconds();
      tfTimed = true;
      tfPending = false;
    }
  }

  Impl(VolumeMesh handle, int field, uint32_t leafSize)
      : mesh(std::move(handle)), fieldIndex(field), renderer(detail::Access::mesh(mesh), field, leafSize) {}
  Impl(VolumeMesh handle, int field, uint32_t leafSize, const MeshPiece &piece)
      : Impl(std::move(handle), field, leafSize) {
    renderer.setPiece(piece.region, piece.wholeBounds, piece.wholeStepScales.meanCellSizeLog2,
                      piece.wholeStepScales.finestStepScale);
  }
};

VolumeRenderer::VolumeRenderer(VolumeMesh mesh, int fieldIndex, uint32_t leafSize)
    : impl_(std::make_unique<Impl>(std::move(mesh), fieldIndex, leafSize)) {
  // Said of the data here, before a default camera or step built from it is refused in other words.
  const VolumeMesh &m = impl_->mesh;
  const Box3f b = m.bounds();
  if (m.cellCount() > 0 && b.lower.x == b.upper.x && b.lower.y == b.upper.y && b.lower.z == b.upper.z)
    throw Error(m.source(), "", "the mesh has zero extent: all its points coincide");
}

VolumeRenderer::VolumeRenderer(VolumeMesh mesh, int fieldIndex, uint32_t leafSize, const MeshPiece &piece)
    : impl_(std::make_unique<Impl>(std::move(mesh), fieldIndex, leafSize, piece)) {}

VolumeRenderer::~VolumeRenderer() = default;
VolumeRenderer::VolumeRenderer(VolumeRenderer &&) noexcept = default;
VolumeRenderer &VolumeRenderer::operator=(VolumeRenderer &&) noexcept = default;

const VolumeMesh &VolumeRenderer::mesh() const { return impl_->mesh; }
int VolumeRenderer::fieldIndex() const { return impl_->fieldIndex; }
uint32_t VolumeRenderer::leafSize() const { return impl_->renderer.leafSize(); }

void VolumeRenderer::setTransferFunction(const ColorMap &map, ValueRange range) {
  if (!(range.min < range.max) || !std::isfinite(range.min) || !std::isfinite(range.max)) {
    std::ostringstream text;
    text << "invalid transfer-function range [" << range.min << ", " << range.max
         << "]: the low end must be below the high end, both finite";
    throw Error(text.str());
  }
  // The transfer function maps values by (value - min) / (max - min) in float: a wider range overflows.
  if (double(range.max) - double(range.min) > double(std::numeric_limits<float>::max()))
    throw Error(impl_->mesh.source(), "",
                "the value range [" + numberText(range.min) + ", " + numberText(range.max) +
                    "] is wider than float arithmetic can span; give a narrower range (--range)");
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  if (impl_->map && sameColorMap(*impl_->map, map) && impl_->range.min == range.min &&
      impl_->range.max == range.max)
    return;
  const bool anyBackend = impl_->renderer.prepared(Backend::Cpu) || impl_->renderer.prepared(Backend::Cuda);
  const Timer timer;
  impl_->renderer.setTransferFunction(TransferFunction(map, range.min, range.max));
  impl_->tfUpdateMs = timer.milliseconds();
  impl_->tfTimed = anyBackend;
  impl_->tfPending = !anyBackend;
  impl_->map = map;
  impl_->range = range;
}

ValueRange VolumeRenderer::colorVarianceRange(Backend backend) const {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  const auto [lowest, highest] = impl_->renderer.varianceExtremes(backend);
  return {lowest, highest};
}

void VolumeRenderer::setColorVarianceRange(ValueRange range) {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->renderer.setVarianceRange(range.min, range.max);
}

void VolumeRenderer::setField(VolumeMesh mesh, int fieldIndex) {
  if (fieldIndex < 0 || fieldIndex >= mesh.fieldCount())
    throw Error(mesh.source(), "", "no field " + std::to_string(fieldIndex) + " to render");
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!sameGrid(impl_->mesh, mesh))
    throw Error(mesh.source(), "",
                "its points or cells differ from those of the mesh rendered (" + impl_->mesh.source() +
                    "): the acceleration data cannot be kept; render it with a new renderer");
  // The renderer switches to the new mesh's arrays before the old handle, and its arrays, may go.
  impl_->renderer.setField(detail::Access::mesh(mesh), fieldIndex);
  impl_->mesh = std::move(mesh);
  impl_->fieldIndex = fieldIndex;
}

void VolumeRenderer::prepare(Backend backend) {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->prepare(backend);
}

FrameResult VolumeRenderer::render(const Camera &camera, const FrameSettings &settings) {
  FrameResult frame;
  render(camera, settings, frame);
  return frame;
}

void VolumeRenderer::render(const Camera &camera, const FrameSettings &settings, FrameResult &result) {
  validateCamera(camera);
  validateSettings(settings);
  checkMemoryLimit("", "",
                   uint64_t(settings.width) * uint64_t(settings.height) *
                       (kFrameBytesPerPixel + (settings.keepPremultipliedRgba ? 4 * sizeof(float) : 0) +
                        (settings.keepPremultipliedRgba16 ? 4 * sizeof(uint16_t) : 0)),
                   "a " + std::to_string(settings.width) + "x" + std::to_string(settings.height) + " frame");
  // The mesh's default step costs a pass over its cells, once: only where a setting asks for it.
  const bool defaults = !(settings.s1 > 0.f && settings.s2 > 0.f && settings.p > 0.f && settings.unit > 0.f);
  const VolumeMesh &mesh = impl_->mesh;
  if (defaults && !(settings.s1 > 0.f && settings.unit > 0.f) && !(mesh.volumeStats().median > 0.0))
    throw Error(mesh.source(), "",
                "no default step: the median cell volume is 0 (at least half of the cells are degenerate); "
                "give a step (s1) and opacity unit");
  const FrameSettings s = defaults ? withDefaultSampling(settings, mesh.defaultStep(),
                                                         defaultUnitDistance(mesh.bounds(), mesh.cellCount()))
                                   : settings;
  validateSettings(s); // a given s2 below the default s1, say so by name
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->map)
    throw Error("no transfer function set");
  impl_->prepare(s.backend);
  RenderSettings internal;
  internal.integrator.mode = s.mode;
  internal.integrator.s1 = s.s1;
  internal.integrator.s2 = s.s2;
  internal.integrator.p = s.p;
  internal.integrator.unit = s.unit;
  internal.integrator.preintegrate = preintegrates(s.compositing, s.mode);
  internal.integrator.followMesh = stepsFollowMesh(s.steps, s.mode);
  internal.integrator.shade = s.shade;
  ShadingSettings &shading = internal.shading;
  shading.headlight = s.light.x == 0.f && s.light.y == 0.f && s.light.z == 0.f;
  shading.light = shading.headlight ? Vec3f{0.f, 0.f, 1.f} : s.light;
  shading.ambient = s.ambient;
  shading.diffuse = s.diffuse;
  shading.specular = s.specular;
  shading.shininess = s.shininess;
  const TransferFunctionView tf = impl_->renderer.transferFunction().view();
  IsoSettings &iso = internal.iso;
  iso.count = uint32_t(s.isoValues.size());
  for (uint32_t i = 0; i < iso.count; ++i) {
    iso.values[i] = s.isoValues[i];
    const Vec4f c = tf.sample(s.isoValues[i]);
    iso.colors[i] = s.isoColor ? *s.isoColor : Vec3f{c.x, c.y, c.z};
  }
  iso.opacity = s.isoOpacity;
  iso.hideVolume = s.isoOnly;
  internal.background = s.background;
  internal.width = s.width;
  internal.height = s.height;
  internal.backend = s.backend;
  internal.keepImage = s.keepImage;
  internal.keepOpacity = s.keepOpacity;
  internal.keepSamplesPerPixel = s.keepSamplesPerPixel;
  internal.keepPremultipliedRgba = s.keepPremultipliedRgba;
  internal.keepPremultipliedRgba16 = s.keepPremultipliedRgba16;
  internal.rayLimits = s.rayLimits.empty() ? nullptr : s.rayLimits.data();

  Frame frame; // the result's buffers, to be reused
  frame.image = std::move(result.image);
  frame.opacity = std::move(result.opacity);
  frame.samplesPerPixel = std::move(result.samplesPerPixel);
  frame.premultipliedRgba = std::move(result.premultipliedRgba);
  frame.premultipliedRgba16 = std::move(result.premultipliedRgba16);
  Renderer &renderer = impl_->renderer;
  const Timer timer;
  renderer.render(camera, internal, frame);
  const double renderMs = timer.milliseconds();
  result.image = std::move(frame.image);
  result.opacity = std::move(frame.opacity);
  result.samplesPerPixel = std::move(frame.samplesPerPixel);
  result.premultipliedRgba = std::move(frame.premultipliedRgba);
  result.premultipliedRgba16 = std::move(frame.premultipliedRgba16);

  FrameStats &stats = result.stats;
  stats = FrameStats{};
  stats.mode = s.mode;
  stats.preintegrated = internal.integrator.preintegrate;
  stats.localSteps = internal.integrator.followMesh;
  stats.width = s.width;
  stats.height = s.height;
  stats.cells = impl_->mesh.cellCount();
  stats.partitions = renderer.partitionCount(s.backend);
  stats.partitionsSkipped = skipsSpace(s.mode) ? renderer.transparentPartitions() : 0;
  stats.samplesTotal = frame.samplesTotal;
  stats.samplesPerPixelMean = double(frame.samplesTotal) / (double(s.width) * double(s.height));
  stats.samplesPerPixelMax = frame.samplesMax;
  stats.buildMs = renderer.buildMs(s.backend);
  // One definition for every front end: the update this frame waited for, 0 when the function is unchanged.
  stats.tfUpdateMs = impl_->tfTimed ? impl_->tfUpdateMs : 0.0;
  impl_->tfTimed = false;
  stats.renderMs = renderMs;
  stats.s1 = s.s1;
  stats.s2 = s.s2;
  stats.p = s.p;
  stats.unit = s.unit;
  stats.leafSize = renderer.leafSize();
  stats.shaded = s.shade;
  stats.gradientBytes = renderer.gradientBytes();
  stats.isoSurfaces = iso.count;
  stats.isoOnly = s.isoOnly;
  stats.field = impl_->mesh.field(impl_->fieldIndex).name;
  stats.range = {renderer.transferFunction().valueMin(), renderer.transferFunction().valueMax()};
  stats.backend = s.backend;
  stats.threads = threadCount();
  stats.hostPeakRssBytes = hostPeakRssBytes();
  stats.memoryLayout = renderer.layout(s.backend);
  if (s.backend == Backend::Cuda) {
    stats.device = renderer.deviceName();
    stats.gpuMemoryBytes = renderer.deviceMemoryBytes();
    stats.gpuSceneBytes = renderer.deviceSceneBytes();
    stats.gpuPeakBytes = renderer.devicePeakBytes();
    stats.gpuKernelMs = frame.kernelMs;
    stats.gpuBuildSteps = renderer.deviceBuildSteps();
  }
}

} // namespace uvr
