#include "render/renderer.h"

#include "core/error.h"
#include "core/timer.h"
#include "mesh/tet_neighbors.h"

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
  metadata_ = computePartitionMetadata(partitions_, *tf_);
  tfUpdateMs_ = timer.milliseconds();
}

SceneView Renderer::sceneView() const {
  SceneView scene;
  scene.mesh = meshView_;
  scene.bvh = bvh_.view();
  scene.occupancy = occupancy_.view();
  scene.tetNeighbors = tetNeighbors_.empty() ? nullptr : tetNeighbors_.data();
  scene.partitions = partitions_.view();
  scene.maxOpacity = metadata_.maxOpacity.data();
  scene.nodeMaxOpacity = metadata_.nodeMaxOpacity.data();
  scene.sigma = metadata_.sigma.data();
  scene.tf = tf_->view();
  return scene;
}

Frame Renderer::render(const Camera &camera, const RenderSettings &settings) const {
  if (!tf_)
    throw Error("no transfer function set");
  const IntegratorSettings &s = settings.integrator;
  if (!(s.s1 > 0.f) || !(s.s2 >= s.s1) || !(s.p >= 1.f) || !(s.unit > 0.f))
    throw Error("invalid sampling settings: need s1 > 0, s2 >= s1, p >= 1 and unit > 0");
  if (settings.width <= 0 || settings.height <= 0)
    throw Error("invalid image size");
  Frame frame;
  frame.image = Image(settings.width, settings.height);
  frame.opacity.assign(size_t(settings.width) * size_t(settings.height), 0.f);
  frame.samplesPerPixel.assign(frame.opacity.size(), 0);
  renderCpu(sceneView(), makeCameraView(camera, settings.width, settings.height), settings, frame);
  for (uint32_t n : frame.samplesPerPixel) {
    frame.samplesTotal += n;
    frame.samplesMax = std::max(frame.samplesMax, n);
  }
  return frame;
}

} // namespace uvr
