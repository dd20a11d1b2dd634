#include "render/renderer.h"

#include "backend/cuda/cuda_renderer.h"
#include "core/error.h"
#include "core/timer.h"
#include "mesh/tet_neighbors.h"
#include "render/pixel.h"

namespace uvr {

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
  if (name == "cuda") {
#ifdef UVR_HAVE_CUDA
    return Backend::Cuda;
#else
    throw Error(
        "this uvr was built without CUDA (no CUDA toolkit was found at build time): use --backend cpu");
#endif
  }
  throw Error("unknown backend '" + name + "': expected cpu or cuda");
}

Renderer::Renderer(const Mesh &mesh, int fieldIndex, uint32_t leafSize) : mesh_(mesh) {
  if (fieldIndex < 0 || size_t(fieldIndex) >= mesh.fields.size())
    throw Error("the mesh has no scalar field to render");
  const Timer timer;
  meshView_ = makeMeshView(mesh_, fieldIndex);
  bvh_ = buildBvh(meshView_);
  occupancy_ = buildOccupancyGrid(meshView_);
  tetNeighbors_ = buildTetNeighbors(mesh_);
  partitions_ = buildPartitions(meshView_, leafSize);
  buildMs_ = timer.milliseconds();
}

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
    metadata_ = computePartitionMetadata(partitions_, transferFunction());
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
  SceneView scene = geometryView();
  const PartitionMetadata &meta = metadata();
  scene.nodeMaxOpacity = meta.nodeMaxOpacity.data();
  scene.sigma = meta.sigma.data();
  scene.tf = tf_->view();
  return scene;
}

SceneView Renderer::geometryView() const {
  SceneView scene;
  scene.mesh = meshView_;
  scene.bvh = bvh_.view();
  scene.occupancy = occupancy_.view();
  scene.tetNeighbors = tetNeighbors_.empty() ? nullptr : tetNeighbors_.data();
  scene.partitions = partitions_.view();
  return scene;
}

SceneSizes Renderer::sceneSizes() const {
  SceneSizes sizes;
  sizes.points = mesh_.points.size();
  sizes.values = meshView_.cellCentered ? mesh_.cellCount() : mesh_.points.size();
  sizes.bvhNodes = bvh_.nodes.size();
  sizes.bvhCellIds = bvh_.cellIds.size();
  sizes.partitionNodes = partitions_.nodes.size();
  sizes.occupancyWords = occupancy_.bits.size();
  return sizes;
}

void Renderer::prepare(Backend backend) const {
  if (backend != Backend::Cuda || cuda_)
    return;
#ifdef UVR_HAVE_CUDA
  // Leaves of up to 8 cells: a fraction of the nodes, and so of the GPU memory, for a few more cell tests.
  const Bvh deviceBvh = collapseBvh(bvh_, 8);
  SceneView scene = geometryView();
  scene.bvh = deviceBvh.view();
  SceneSizes sizes = sceneSizes();
  sizes.bvhNodes = deviceBvh.nodes.size();
  cuda_ = std::make_shared<CudaRenderer>(scene, sizes);
  if (tf_)
    cuda_->setTransferFunction(*tf_);
#else
  throw Error("this uvr was built without CUDA: use --backend cpu");
#endif
}

#ifdef UVR_HAVE_CUDA
std::string Renderer::deviceName() const { return cuda_ ? std::string(cuda_->deviceName()) : std::string(); }
size_t Renderer::deviceMemoryBytes() const { return cuda_ ? cuda_->memoryBytes() : 0; }
size_t Renderer::deviceSceneBytes() const { return cuda_ ? cuda_->sceneBytes() : 0; }
PartitionMetadata Renderer::deviceMetadata() const { return cuda_ ? cuda_->metadata() : PartitionMetadata{}; }
#else
std::string Renderer::deviceName() const { return {}; }
size_t Renderer::deviceMemoryBytes() const { return 0; }
size_t Renderer::deviceSceneBytes() const { return 0; }
PartitionMetadata Renderer::deviceMetadata() const { return {}; }
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
  frame.opacity.resize(pixels);
  frame.samplesPerPixel.resize(pixels);
  frame.samplesTotal = 0;
  frame.samplesMax = 0;
  frame.kernelMs = 0.0;
  PixelTarget target;
  target.rgb = frame.image.rgb.data();
  target.opacity = frame.opacity.data();
  target.samples = frame.samplesPerPixel.data();
  target.width = settings.width;
  target.background = settings.background;
  const CameraView view = makeCameraView(camera, settings.width, settings.height);
  if (settings.backend == Backend::Cuda) {
    prepare(Backend::Cuda);
#ifdef UVR_HAVE_CUDA
    frame.kernelMs = cuda_->render(view, settings.integrator, target, settings.height);
#endif
  } else {
    renderCpu(sceneView(), view, settings, target);
  }
  for (uint32_t n : frame.samplesPerPixel) {
    frame.samplesTotal += n;
    frame.samplesMax = std::max(frame.samplesMax, n);
  }
}

} // namespace uvr
