#include "engine/renderer.h"

#include "backend/cpu/cpu_backend.h"
#include "mesh/point_gradients.h"
#include "render/pixel.h"
#include <uvr/error.h>
#include <uvr/system.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace uvr {

namespace {

void checkFieldIndex(const Mesh &mesh, int fieldIndex) {
  if (fieldIndex < 0 || size_t(fieldIndex) >= mesh.fields.size())
    throw Error("the mesh has no scalar field to render");
}

} // namespace

Renderer::Renderer(const Mesh &mesh, int fieldIndex, uint32_t leafSize) : mesh_(&mesh), leafSize_(leafSize) {
  checkFieldIndex(mesh, fieldIndex);
  meshView_ = makeMeshView(mesh, fieldIndex);
  const Box3f bounds = mesh.bounds();
  diagonal_ = bounds.lower.x <= bounds.upper.x ? length(bounds.upper - bounds.lower) : 0.f;
  center_ = bounds.lower.x <= bounds.upper.x ? bounds.center() : Vec3f{};
}

Renderer::~Renderer() = default;

void Renderer::setPiece(const Box3f &region, const Box3f &wholeBounds, double meanCellSizeLog2,
                        float finestStepScale) {
  if (prepared(Backend::Cpu) || prepared(Backend::Cuda))
    throw Error("a renderer's piece is set before its backends are prepared");
  if (region.empty() || wholeBounds.empty())
    throw Error("a piece of a mesh needs a region and the whole mesh's bounds");
  region_ = region;
  // As the partitions pad the root of a whole mesh's tree, where its rays' sample grids begin.
  gridBounds_ = padded(wholeBounds, partitionPadding(wholeBounds));
  diagonal_ = length(wholeBounds.upper - wholeBounds.lower);
  center_ = wholeBounds.center();
  meshView_.stepScaleReference = meanCellSizeLog2;
  wholeFinestStepScale_ = finestStepScale;
  meshView_.pieceRegion = region;
  meshView_.pieceWholeBounds = wholeBounds;
}

void Renderer::setTransferFunction(TransferFunction tf) {
  const Timer timer;
  tf_.emplace(std::move(tf));
  tf_->setVarianceRange(varianceLowest_, varianceHighest_);
  for (const std::unique_ptr<RenderBackend> &b : backends_)
    if (b)
      transparentPartitions_ = b->setTransferFunction(*tf_);
  tfUpdateMs_ = timer.milliseconds();
}

void Renderer::setField(const Mesh &mesh, int fieldIndex) {
  checkFieldIndex(mesh, fieldIndex);
  mesh_ = &mesh;
  meshView_ = makeMeshView(mesh, fieldIndex);
  for (const std::unique_ptr<RenderBackend> &b : backends_)
    if (b)
      transparentPartitions_ = b->setField(meshView_);
  if (gradientsBuilt_)
    buildGradients();
}

void Renderer::buildGradients() {
  gradients_ = computePointGradients(meshView_, mesh_->points.size());
  gradientsBuilt_ = true;
  for (const std::unique_ptr<RenderBackend> &b : backends_)
    if (b)
      b->setGradients(gradients_.data(), gradients_.size());
}

const TransferFunction &Renderer::transferFunction() const {
  if (!tf_)
    throw Error("no transfer function set");
  return *tf_;
}

void Renderer::prepare(Backend which) {
  std::unique_ptr<RenderBackend> &b = backends_[size_t(which)];
  if (b)
    return;
  b = makeBackend(which, *mesh_, meshView_, leafSize(), memoryLayout());
  if (gradientsBuilt_)
    b->setGradients(gradients_.data(), gradients_.size());
  if (tf_)
    transparentPartitions_ = b->setTransferFunction(*tf_);
}

bool Renderer::prepared(Backend which) const { return backends_[size_t(which)] != nullptr; }

RenderBackend &Renderer::backend(Backend which) const {
  if (!prepared(which))
    throw Error(std::string("the ") + backendName(which) + " backend has not been prepared");
  return *backends_[size_t(which)];
}

const CpuBackend &Renderer::cpu() const { return static_cast<const CpuBackend &>(backend(Backend::Cpu)); }

uint32_t Renderer::leafSize() const {
  return leafSize_ != kAutoLeafSize ? leafSize_ : defaultLeafSize(mesh_->cellCount());
}

uint32_t Renderer::partitionCount(Backend which) const { return backend(which).partitionCount(); }
double Renderer::buildMs(Backend which) const { return backend(which).buildMs(); }
const Partitions &Renderer::partitions() const { return cpu().data().partitions; }
const PartitionMetadata &Renderer::metadata() const { return cpu().currentMetadata(); }

std::string Renderer::deviceName() const {
  return prepared(Backend::Cuda) ? backend(Backend::Cuda).deviceName() : std::string();
}
size_t Renderer::deviceMemoryBytes() const {
  return prepared(Backend::Cuda) ? backend(Backend::Cuda).deviceMemoryBytes() : 0;
}
size_t Renderer::deviceSceneBytes() const {
  return prepared(Backend::Cuda) ? backend(Backend::Cuda).deviceSceneBytes() : 0;
}
MemoryLayout Renderer::layout(Backend which) const { return backend(which).layout(); }
size_t Renderer::devicePeakBytes() const {
  return prepared(Backend::Cuda) ? backend(Backend::Cuda).devicePeakBytes() : 0;
}
std::vector<std::pair<std::string, double>> Renderer::deviceBuildSteps() const {
  return prepared(Backend::Cuda) ? backend(Backend::Cuda).buildSteps()
                                 : std::vector<std::pair<std::string, double>>{};
}
HostAcceleration Renderer::deviceAcceleration() const { return backend(Backend::Cuda).acceleration(); }
PartitionMetadata Renderer::deviceMetadata() const { return backend(Backend::Cuda).metadata(); }

void Renderer::setVarianceRange(float lowest, float highest) {
  varianceLowest_ = lowest;
  varianceHighest_ = highest;
  if (tf_)
    setTransferFunction(*tf_);
}

std::pair<float, float> Renderer::varianceExtremes(Backend b) const {
  if (b == Backend::Cpu) {
    const PartitionMetadata &meta = metadata();
    return {meta.varianceLowest, meta.varianceHighest};
  }
  const PartitionMetadata meta = deviceMetadata();
  return {meta.varianceLowest, meta.varianceHighest};
}

Frame Renderer::render(const Camera &camera, const RenderSettings &settings) {
  Frame frame;
  render(camera, settings, frame);
  return frame;
}

void Renderer::render(const Camera &camera, const RenderSettings &settings, Frame &frame) {
  if (!tf_)
    throw Error("no transfer function set");
  const IntegratorSettings &s = settings.integrator;
  if (!(s.s1 > 0.f) || !(s.s2 >= s.s1) || !(s.p >= 1.f) || !(s.unit > 0.f))
    throw Error("invalid sampling settings: need s1 > 0, s2 >= s1, p >= 1 and unit > 0");
  if (diagonal_ / s.s1 > kMostSamplesPerRay) {
    std::ostringstream what;
    what << "step s1 = " << s.s1 << " takes " << diagonal_ / s.s1
         << " samples along the mesh's diagonal, more than the " << kMostSamplesPerRay << " a ray may take";
    throw Error(what.str());
  }
  // A ray's samples lie at t = t_enter + k * spacing in float: from an eye so far that the spacing is below
  // t's precision they would not advance. Spacings go down to s1 / 16 where steps follow the mesh.
  const float finest = s.followMesh ? s.s1 / 16.f : s.s1;
  const float reach = length(camera.eye - center_) + diagonal_;
  if (!(reach / finest < float(1 << 23))) {
    std::ostringstream what;
    what << "the camera's eye (" << camera.eye.x << ", " << camera.eye.y << ", " << camera.eye.z
         << ") is too far from the mesh for step s1 = " << s.s1
         << ": float positions along its rays cannot resolve the step; move it closer or take a larger s1";
    throw Error(what.str());
  }
  if (settings.width <= 0 || settings.height <= 0)
    throw Error("invalid image size");
  prepare(settings.backend);
  // Every pixel is written below, so buffers of the right size are reused as they are: no allocation, and
  // no page faults on fresh memory, from one frame to the next.
  const size_t pixels = size_t(settings.width) * size_t(settings.height);
  frame.image.width = settings.width;
  frame.image.height = settings.height;
  frame.image.rgb.resize(settings.keepImage ? 3 * pixels : 0);
  frame.opacity.resize(settings.keepOpacity ? pixels : 0);
  frame.samplesPerPixel.resize(settings.keepSamplesPerPixel ? pixels : 0);
  frame.premultipliedRgba.resize(settings.keepPremultipliedRgba ? 4 * pixels : 0);
  frame.premultipliedRgba16.resize(settings.keepPremultipliedRgba16 ? 4 * pixels : 0);
  PixelTarget target;
  target.rgb = settings.keepImage ? frame.image.rgb.data() : nullptr;
  target.opacity = settings.keepOpacity ? frame.opacity.data() : nullptr;
  target.samples = settings.keepSamplesPerPixel ? frame.samplesPerPixel.data() : nullptr;
  target.rgba = settings.keepPremultipliedRgba ? frame.premultipliedRgba.data() : nullptr;
  target.rgba16 = settings.keepPremultipliedRgba16 ? frame.premultipliedRgba16.data() : nullptr;
  target.width = settings.width;
  target.background = settings.background;
  IntegratorSettings derived = s;
  derived.finestStepSigma = finestStepSigma(s.s1, s.s2, s.p);
  derived.clip = region_;
  derived.gridBounds = gridBounds_;
  derived.finestStepScale = wholeFinestStepScale_;
  const CameraView view = makeCameraView(camera, settings.width, settings.height, settings.rayLimits);
  if (settings.iso.count > kMaxIsoValues)
    throw Error("at most " + std::to_string(kMaxIsoValues) + " isosurfaces");
  if (settings.iso.hideVolume && settings.iso.count == 0)
    throw Error("hiding the volume needs an isosurface to draw");
  // Ascending: the march composites a segment's surfaces in the order of their values.
  IsoSettings iso = settings.iso;
  for (uint32_t i = 1; i < iso.count; ++i)
    for (uint32_t j = i; j > 0 && iso.values[j] < iso.values[j - 1]; --j) {
      std::swap(iso.values[j], iso.values[j - 1]);
      std::swap(iso.colors[j], iso.colors[j - 1]);
    }
  derived.iso = iso.count > 0;
  if (iso.hideVolume)
    derived.preintegrate = false; // no volume to integrate
  transparentPartitions_ = backend(settings.backend).setIsoSurfaces(iso);
  ShadingSettings shading = settings.shading;
  if (s.shade || derived.iso) {
    if (!gradientsBuilt_)
      buildGradients();
    const Vec3f light = settings.shading.light; // in camera space: x right, y up, z towards the eye
    shading.light =
        normalize(normalize(view.right) * light.x + normalize(view.up) * light.y - view.forward * light.z);
    // Fully lit where the field changes by kFullyLitChange of the function's range across a mean cell.
    const float range = tf_->valueMax() - tf_->valueMin();
    const float meanCell = diagonal_ / std::cbrt(float(std::max<uint64_t>(mesh_->cellCount(), 1)));
    shading.fullGradientInverse = range > 0.f ? meanCell / (kFullyLitChange * range) : 0.f;
  }
  const SampleTotals samples =
      backend(settings.backend).render(view, derived, shading, target, frame.kernelMs);
  frame.samplesTotal = samples.total;
  frame.samplesMax = samples.max;
}

} // namespace uvr
