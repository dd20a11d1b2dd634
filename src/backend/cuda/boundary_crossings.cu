#include "backend/cuda/boundary_crossings.cuh"

#include "render/boundary_crossings.h"

#include <cub/device/device_scan.cuh>
#include <cub/device/device_segmented_sort.cuh>

namespace uvr {
namespace {

// Faces per block.
constexpr unsigned kCrossingsBlock = 128;

/// Each boundary face's crossings with the rays of the pixels it covers: with no `keys`, counted into
/// start[pixel + 1]; with them, placed at start[pixel + 1], which moves on by one each (findBoundaryCrossings
/// says how start's entries change).
__global__ void crossingsKernel(MeshView mesh, const uint32_t *faces, uint64_t faceCount, CameraView camera,
                                uint64_t *start, uint64_t *keys) {
  const uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i >= faceCount)
    return;
  auto *slots = reinterpret_cast<unsigned long long *>(start) + 1;
  forEachPixelCrossing(mesh, faces[i], camera, [&](uint64_t pixel, uint64_t key) {
    const unsigned long long slot = atomicAdd(slots + pixel, 1ull);
    if (keys)
      keys[slot] = key;
  });
}

} // namespace

void DeviceCrossings::find(const MeshView &mesh, const DeviceBuffer<uint32_t> &faceList,
                           const CameraView &camera, size_t pixels) {
  const uint64_t faces = faceList.size();
  const unsigned blocks = blocksFor(faces, kCrossingsBlock);
  // What the host's findBoundaryCrossings makes, by testing the faces twice: once to count each pixel's
  // crossings, once to place them from its start on; then ordered pixel by pixel.
  start_.resize(pixels + 2);
  UVR_CUDA_CHECK(cudaMemsetAsync(start_.data(), 0, start_.bytes()));
  crossingsKernel<<<blocks, kCrossingsBlock>>>(mesh, faceList.data(), faces, camera, start_.data(), nullptr);
  UVR_CUDA_CHECK(cudaGetLastError());
  uint64_t *counts = start_.data() + 1;
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceScan::ExclusiveSum(storage, bytes, counts, counts, int64_t(pixels + 1));
  });
  uint64_t total = 0;
  UVR_CUDA_CHECK(cudaMemcpy(&total, counts + pixels, sizeof total, cudaMemcpyDeviceToHost));
  if (total == 0)
    return;
  placed_.grow(total, 0);
  keys_.grow(total, 0);
  crossingsKernel<<<blocks, kCrossingsBlock>>>(mesh, faceList.data(), faces, camera, start_.data(),
                                               placed_.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  const uint64_t *start = start_.data();
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceSegmentedSort::SortKeys(storage, bytes, placed_.data(), keys_.data(), int64_t(total),
                                              int64_t(pixels), start, start + 1);
  });
}

} // namespace uvr
