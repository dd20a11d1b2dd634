#include "backend/cuda/cuda_renderer.h"

#include "core/error.h"

#include <cuda_runtime.h>

#include <string>
#include <vector>

namespace uvr {
namespace {

void check(cudaError_t status, const char *call, const char *file, int line) {
  if (status == cudaSuccess)
    return;
  std::string what = std::string("CUDA: ") + call + " failed at " + file + ":" + std::to_string(line) + ": " +
                     cudaGetErrorString(status);
  if (status == cudaErrorMemoryAllocation) {
    size_t free = 0, total = 0;
    if (cudaMemGetInfo(&free, &total) == cudaSuccess)
      what += " (" + std::to_string(free) + " of " + std::to_string(total) + " bytes free)";
  }
  throw Error(what);
}
#define UVR_CUDA_CHECK(call) check((call), #call, __FILE__, __LINE__)

/// One device allocation, freed with its owner.
template <typename T> class DeviceBuffer {
public:
  DeviceBuffer() = default;
  ~DeviceBuffer() { cudaFree(data_); }
  DeviceBuffer(const DeviceBuffer &) = delete;
  DeviceBuffer &operator=(const DeviceBuffer &) = delete;

  void resize(size_t count) {
    if (count == count_)
      return;
    cudaFree(data_);
    data_ = nullptr;
    count_ = 0;
    if (count == 0)
      return;
    const cudaError_t status = cudaMalloc(&data_, count * sizeof(T));
    if (status != cudaSuccess) {
      cudaGetLastError(); // clear the sticky state before reporting
      size_t free = 0, total = 0;
      cudaMemGetInfo(&free, &total);
      throw Error("GPU out of memory: asked for " + std::to_string(count * sizeof(T)) + " bytes, " +
                  std::to_string(free) + " of " + std::to_string(total) + " free");
    }
    count_ = count;
  }
  /// Copies `count` elements from host memory (allocating as needed); returns the device pointer.
  T *upload(const T *host, size_t count) {
    resize(count);
    if (count > 0)
      UVR_CUDA_CHECK(cudaMemcpy(data_, host, count * sizeof(T), cudaMemcpyHostToDevice));
    return data_;
  }
  void download(T *host, size_t count) const {
    if (count > 0)
      UVR_CUDA_CHECK(cudaMemcpy(host, data_, count * sizeof(T), cudaMemcpyDeviceToHost));
  }
  T *data() const { return data_; }
  size_t bytes() const { return count_ * sizeof(T); }

private:
  T *data_ = nullptr;
  size_t count_ = 0;
};

__global__ void renderKernel(SceneView scene, IntegratorSettings settings, CameraView camera,
                             PixelTarget target, int height) {
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  if (x >= target.width || y >= height)
    return;
  uint32_t hint = kNoCell; // no neighbouring ray to start from: the BVH finds the first cell
  target.store(x, y, integrateRay(scene, settings, camera.ray(x, y), hint));
}

} // namespace

struct CudaRenderer::Impl {
  std::string deviceName;
  SceneView scene; // device pointers
  DeviceBuffer<Vec3f> points;
  DeviceBuffer<uint32_t> tets, pyramids, wedges, hexes, tetNeighbors, bvhCellIds;
  DeviceBuffer<float> values, maxOpacity, nodeMaxOpacity, sigma;
  DeviceBuffer<BvhNode> bvhNodes;
  DeviceBuffer<KdNode> kdNodes;
  DeviceBuffer<Box3f> nodeBounds, partitionBounds;
  DeviceBuffer<uint64_t> occupancy;
  DeviceBuffer<Vec4f> tfTable;
  DeviceBuffer<uint8_t> rgb;
  DeviceBuffer<float> opacity;
  DeviceBuffer<uint32_t> samples;
  cudaEvent_t kernelStart = nullptr, kernelEnd = nullptr; // around the render kernel

  ~Impl() {
    if (kernelStart)
      cudaEventDestroy(kernelStart);
    if (kernelEnd)
      cudaEventDestroy(kernelEnd);
  }
};

CudaRenderer::CudaRenderer(const SceneView &host, const SceneSizes &sizes) : impl_(std::make_unique<Impl>()) {
  int devices = 0;
  const cudaError_t status = cudaGetDeviceCount(&devices);
  if (status != cudaSuccess || devices == 0)
    throw Error(std::string("no CUDA GPU available") +
                (status != cudaSuccess ? std::string(": ") + cudaGetErrorString(status) : std::string()));
  cudaDeviceProp properties{};
  UVR_CUDA_CHECK(cudaGetDeviceProperties(&properties, 0));
  impl_->deviceName = properties.name;

  Impl &d = *impl_;
  UVR_CUDA_CHECK(cudaEventCreate(&d.kernelStart));
  UVR_CUDA_CHECK(cudaEventCreate(&d.kernelEnd));
  SceneView &scene = d.scene;
  scene = host;
  const MeshView &mesh = host.mesh;
  scene.mesh.points = d.points.upload(mesh.points, sizes.points);
  scene.mesh.tets = d.tets.upload(mesh.tets, 4 * mesh.tetCount);
  scene.mesh.pyramids = d.pyramids.upload(mesh.pyramids, 5 * mesh.pyramidCount);
  scene.mesh.wedges = d.wedges.upload(mesh.wedges, 6 * mesh.wedgeCount);
  scene.mesh.hexes = d.hexes.upload(mesh.hexes, 8 * mesh.hexCount);
  scene.mesh.values = d.values.upload(mesh.values, sizes.values);
  scene.tetNeighbors =
      host.tetNeighbors ? d.tetNeighbors.upload(host.tetNeighbors, 4 * mesh.tetCount) : nullptr;
  scene.bvh.nodes = d.bvhNodes.upload(host.bvh.nodes, sizes.bvhNodes);
  scene.bvh.cellIds = d.bvhCellIds.upload(host.bvh.cellIds, sizes.bvhCellIds);
  scene.occupancy.bits =
      host.occupancy.bits ? d.occupancy.upload(host.occupancy.bits, sizes.occupancyWords) : nullptr;
  scene.partitions.nodes = d.kdNodes.upload(host.partitions.nodes, sizes.partitionNodes);
  scene.partitions.nodeBounds = d.nodeBounds.upload(host.partitions.nodeBounds, sizes.partitionNodes);
  scene.partitions.bounds = d.partitionBounds.upload(host.partitions.bounds, host.partitions.count);
  updateTransferFunction(host, sizes);
}

CudaRenderer::~CudaRenderer() = default;

void CudaRenderer::updateTransferFunction(const SceneView &host, const SceneSizes &sizes) {
  Impl &d = *impl_;
  d.scene.tf = host.tf;
  d.scene.tf.table = d.tfTable.upload(host.tf.table, size_t(host.tf.size));
  d.scene.maxOpacity = d.maxOpacity.upload(host.maxOpacity, host.partitions.count);
  d.scene.sigma = d.sigma.upload(host.sigma, host.partitions.count);
  d.scene.nodeMaxOpacity = d.nodeMaxOpacity.upload(host.nodeMaxOpacity, sizes.partitionNodes);
}

double CudaRenderer::render(const CameraView &camera, const IntegratorSettings &settings,
                            const PixelTarget &target, int height) {
  Impl &d = *impl_;
  const size_t pixels = size_t(target.width) * size_t(height);
  d.rgb.resize(3 * pixels);
  d.opacity.resize(pixels);
  d.samples.resize(pixels);
  PixelTarget device = target;
  device.rgb = d.rgb.data();
  device.opacity = d.opacity.data();
  device.samples = d.samples.data();
  const dim3 block(16, 8);
  const dim3 grid((unsigned(target.width) + block.x - 1) / block.x,
                  (unsigned(height) + block.y - 1) / block.y);
  UVR_CUDA_CHECK(cudaEventRecord(d.kernelStart));
  renderKernel<<<grid, block>>>(d.scene, settings, camera, device, height);
  UVR_CUDA_CHECK(cudaGetLastError());
  UVR_CUDA_CHECK(cudaEventRecord(d.kernelEnd));
  UVR_CUDA_CHECK(cudaDeviceSynchronize()); // a kernel fault surfaces here
  float kernelMs = 0.f;
  UVR_CUDA_CHECK(cudaEventElapsedTime(&kernelMs, d.kernelStart, d.kernelEnd));
  d.rgb.download(target.rgb, 3 * pixels);
  d.opacity.download(target.opacity, pixels);
  d.samples.download(target.samples, pixels);
  return kernelMs;
}

size_t CudaRenderer::memoryBytes() const {
  const Impl &d = *impl_;
  return sceneBytes() + d.rgb.bytes() + d.opacity.bytes() + d.samples.bytes();
}

size_t CudaRenderer::sceneBytes() const {
  const Impl &d = *impl_;
  return d.points.bytes() + d.tets.bytes() + d.pyramids.bytes() + d.wedges.bytes() + d.hexes.bytes() +
         d.tetNeighbors.bytes() + d.bvhCellIds.bytes() + d.values.bytes() + d.maxOpacity.bytes() +
         d.nodeMaxOpacity.bytes() + d.sigma.bytes() + d.bvhNodes.bytes() + d.kdNodes.bytes() +
         d.nodeBounds.bytes() + d.partitionBounds.bytes() + d.occupancy.bytes() + d.tfTable.bytes();
}

const std::string &CudaRenderer::deviceName() const { return impl_->deviceName; }

} // namespace uvr
