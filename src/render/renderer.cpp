#include "render/renderer.h"

#include "backend/cuda/cuda_renderer.h"
#include "core/error.h"
#include "core/timer.h"
#include "mesh/cell_neighbors.h"
#include "mesh/tet_neighbors.h"
#include "render/pixel.h"

#include <unistd.h>

#include <algorithm>

namespace uvr {

namespace {

/// Whether a structure that only speeds walks up may take `bytes`: the per-tet records (64 bytes a tet) and
/// the other cells' adjacency (cellAdjacencyBytes) would cost more than a large mesh on a small machine could
/// spare, so each is kept to an eighth of the memory.
bool walkAidFits(uint64_t bytes) {
  const long pages = sysconf(_SC_PHYS_PAGES), pageBytes = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && pageBytes > 0 && bytes <= uint64_t(pages) * uint64_t(pageBytes) / 8;
}

} // namespace

Renderer::Renderer(const Mesh &mesh, int fieldIndex, uint32_t leafSize) : mesh_(mesh), leafSize_(leafSize) {
  if (fieldIndex < 0 || size_t(fieldIndex) >= mesh.fields.size())
    throw Error("the mesh has no scalar field to render");
  meshView_ = makeMeshView(mesh_, fieldIndex);
}

Renderer::~Renderer() = default;

const HostAcceleration &Renderer::host() const {
  if (!host_) {
    const Timer timer;
    auto built = std::make_unique<HostAcceleration>();
    built->bvh = buildBvh(meshView_);
    built->occupancy = buildOccupancyGrid(meshView_);
    built->tetNeighbors = buildTetNeighbors(mesh_);
    const uint64_t otherCells = meshView_.cellCount() - meshView_.tetCount;
    if (walkAidFits(cellAdjacencyBytes(otherCells))) {
      built->cellNeighbors = buildCellNeighbors(mesh_);
      built->cellFacePlanes = buildCellFacePlanes(meshView_);
    }
    built->seeds =
        buildSeedGrid(meshView_, built->tetNeighbors.empty() ? nullptr : built->tetNeighbors.data());
    if (!built->tetNeighbors.empty() && listsBoundaryFaces(meshView_))
      built->boundaryFaceList = listBoundaryFaces(built->tetNeighbors);
    built->partitions = buildPartitions(meshView_, leafSize());
    if (!built->tetNeighbors.empty() && walkAidFits(meshView_.tetCount * sizeof(TetAffine)))
      built->tetAffine = buildTetAffine(meshView_);
    hostBuildMs_ = timer.milliseconds();
    host_ = std::move(built);
  }
  return *host_;
}

const Partitions &Renderer::partitions() const { return host().partitions; }

void Renderer::setTransferFunction(TransferFunction tf) {
  const Timer timer;
  tf_.emplace(std::move(tf));
  metadataCurrent_ = false;
#ifdef UVR_HAVE_CUDA
  if (cuda_)
    transparentPartitions_ = cuda_->setTransferFunction(*tf_);
  else
#endif
    transparentPartitions_ = metadata().transparentCount;
  tfUpdateMs_ = timer.milliseconds();
}

const PartitionMetadata &Renderer::metadata() const {
  if (!metadataCurrent_) {
    metadata_ = computePartitionMetadata(partitions(), transferFunction());
    metadataCurrent_ = true;
  }
  return metadata_;
}

const TransferFunction &Renderer::transferFunction() const {
  if (!tf_)
    throw Error("no transfer function set");
  return *tf_;
}

SceneView Renderer::sceneView() const {
  const HostAcceleration &accel = host();
  SceneView scene;
  scene.mesh = meshView_;
  scene.bvh = accel.bvh.view();
  scene.occupancy = accel.occupancy.view();
  scene.seeds = accel.seeds.view();
  scene.tetNeighbors = accel.tetNeighbors.empty() ? nullptr : accel.tetNeighbors.data();
  scene.cellNeighbors = accel.cellNeighbors.empty() ? nullptr : accel.cellNeighbors.data();
  scene.cellFacePlanes = accel.cellFacePlanes.empty() ? nullptr : accel.cellFacePlanes.data();
  scene.tetAffine = accel.tetAffine.empty() ? nullptr : accel.tetAffine.data();
  scene.partitions = accel.partitions.view();
  const PartitionMetadata &meta = metadata();
  scene.nodeMaxOpacity = meta.nodeMaxOpacity.data();
  scene.nodeMinSigma = meta.nodeMinSigma.data();
  scene.sigma = meta.sigma.data();
  scene.tf = tf_->view();
  return scene;
}

void Renderer::prepare(Backend backend) const {
  if (backend == Backend::Cpu) {
    host();
    return;
  }
  if (cuda_)
    return;
#ifdef UVR_HAVE_CUDA
  cuda_ = std::make_shared<CudaRenderer>(meshView_, mesh_.points.size(), leafSize());
  if (tf_)
    cuda_->setTransferFunction(*tf_);
#else
  throw Error("this uvr was built without CUDA: use --backend cpu");
#endif
}

uint32_t Renderer::leafSize() const {
  return leafSize_ != kAutoLeafSize ? leafSize_ : defaultLeafSize(mesh_.cellCount());
}

uint32_t Renderer::partitionCount(Backend backend) const {
  prepare(backend);
#ifdef UVR_HAVE_CUDA
  if (backend == Backend::Cuda)
    return cuda_->partitionCount();
#endif
  return host().partitions.count();
}

double Renderer::buildMs(Backend backend) const {
#ifdef UVR_HAVE_CUDA
  if (backend == Backend::Cuda)
    return cuda_ ? cuda_->buildMs() : 0.0;
#endif
  return backend == Backend::Cpu ? hostBuildMs_ : 0.0;
}

#ifdef UVR_HAVE_CUDA
std::string Renderer::deviceName() const { return cuda_ ? std::string(cuda_->deviceName()) : std::string(); }
size_t Renderer::deviceMemoryBytes() const { return cuda_ ? cuda_->memoryBytes() : 0; }
size_t Renderer::deviceSceneBytes() const { return cuda_ ? cuda_->sceneBytes() : 0; }
PartitionMetadata Renderer::deviceMetadata() const { return cuda_ ? cuda_->metadata() : PartitionMetadata{}; }
std::vector<std::pair<std::string, double>> Renderer::deviceBuildSteps() const {
  return cuda_ ? cuda_->buildSteps() : std::vector<std::pair<std::string, double>>{};
}
HostAcceleration Renderer::deviceAcceleration() const {
  if (!cuda_)
    throw Error("CUDA has not been prepared");
  return cuda_->acceleration();
}
#else
std::string Renderer::deviceName() const { return {}; }
size_t Renderer::deviceMemoryBytes() const { return 0; }
size_t Renderer::deviceSceneBytes() const { return 0; }
PartitionMetadata Renderer::deviceMetadata() const { return {}; }
std::vector<std::pair<std::string, double>> Renderer::deviceBuildSteps() const { return {}; }
HostAcceleration Renderer::deviceAcceleration() const {
  throw Error("this uvr was built without CUDA: use --backend cpu");
}
#endif

Frame Renderer::render(const Camera &camera, const RenderSettings &settings) const {
  Frame frame;
  render(camera, settings, frame);
  return frame;
}

void Renderer::render(const Camera &camera, const RenderSettings &settings, Frame &frame) const {
  if (!tf_)
    throw Error("no transfer function set");
  const IntegratorSettings &s = settings.integrator;
  if (!(s.s1 > 0.f) || !(s.s2 >= s.s1) || !(s.p >= 1.f) || !(s.unit > 0.f))
    throw Error("invalid sampling settings: need s1 > 0, s2 >= s1, p >= 1 and unit > 0");
  if (settings.width <= 0 || settings.height <= 0)
    throw Error("invalid image size");
  // Every pixel is written below, so buffers of the right size are reused as they are: no allocation, and
  // no page faults on fresh memory, from one frame to the next.
  const size_t pixels = size_t(settings.width) * size_t(settings.height);
  frame.image.width = settings.width;
  frame.image.height = settings.height;
  frame.image.rgb.resize(3 * pixels);
  frame.opacity.resize(settings.keepOpacity ? pixels : 0);
  frame.samplesPerPixel.resize(settings.keepSamplesPerPixel ? pixels : 0);
  frame.kernelMs = 0.0;
  PixelTarget target;
  target.rgb = frame.image.rgb.data();
  target.opacity = settings.keepOpacity ? frame.opacity.data() : nullptr;
  target.samples = settings.keepSamplesPerPixel ? frame.samplesPerPixel.data() : nullptr;
  target.width = settings.width;
  target.background = settings.background;
  const CameraView view = makeCameraView(camera, settings.width, settings.height);
  RenderSettings derived = settings;
  derived.integrator.finestStepSigma = finestStepSigma(s.s1, s.s2, s.p);
  SampleTotals samples;
  if (settings.backend == Backend::Cuda) {
    prepare(Backend::Cuda);
#ifdef UVR_HAVE_CUDA
    frame.kernelMs = cuda_->render(view, derived.integrator, target, settings.height, samples);
#endif
  } else {
    samples = renderCpu(sceneView(), host().boundaryFaceList, view, derived, target);
  }
  frame.samplesTotal = samples.total;
  frame.samplesMax = samples.max;
}

} // namespace uvr
