// The GPU build's steps run in order (the steps themselves: see device_builder.cuh), with the cell centroids
// and the mesh's box that the later steps start from, and the cell sort that the BVH and the partitions
// share.
#include "backend/cuda/device_builder.cuh"

#include "mesh/cell.h"
#include <uvr/system.h>

#include <cub/device/device_radix_sort.cuh>

#include <algorithm>

namespace uvr {
namespace gpu_build {
namespace {

__global__ void indicesKernel(uint64_t count, uint32_t *indices) {
  const uint64_t i = globalIndex();
  if (i < count)
    indices[i] = uint32_t(i);
}

// ---- Cell boxes

/// The centroid of every cell (partitionCentroid) and, reduced warp by warp into `bounds`, the mesh's box.
__global__ void centroidsKernel(MeshView mesh, uint64_t cells, Vec3f *centroids, AtomicBox *bounds) {
  Box3f local;
  for (uint64_t c = globalIndex(); c < cells; c += uint64_t(gridDim.x) * blockDim.x) {
    const Box3f box = cellBounds(mesh, c);
    centroids[c] = partitionCentroid(box);
    local.extend(box);
  }
  float lo[3] = {local.lower.x, local.lower.y, local.lower.z},
        hi[3] = {local.upper.x, local.upper.y, local.upper.z};
  for (int offset = 16; offset > 0; offset /= 2)
    for (int k = 0; k < 3; ++k) {
      lo[k] = fminf(lo[k], __shfl_xor_sync(0xffffffffu, lo[k], offset));
      hi[k] = fmaxf(hi[k], __shfl_xor_sync(0xffffffffu, hi[k], offset));
    }
  if (threadIdx.x % 32 == 0)
    bounds->extend({{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}});
}

} // namespace

void DeviceBuilder::build() {
  if (cells_ == 0)
    throw Error("the mesh has no volume cells");
  if (cells_ >= UINT32_MAX)
    throw Error("more than 2^32 - 1 cells are not supported by the GPU build");
  if (leafSize_ == 0)
    throw Error("the partition leaf size must be at least 1");
  Progress progress("building acceleration on the GPU", 7);
  step("cell centroids", &DeviceBuilder::centroids, progress);
  step("tet adjacency", &DeviceBuilder::tetAdjacency, progress);
  step("occupancy grid", &DeviceBuilder::occupancy, progress);
  step("seed grid", &DeviceBuilder::seeds, progress);
  step("boundary faces", &DeviceBuilder::boundaryFaceList, progress);
  step("point-location hierarchy", &DeviceBuilder::bvh, progress);
  step("partitions", &DeviceBuilder::partitions, progress);
  progress.finish();
}

void DeviceBuilder::step(const char *name, void (DeviceBuilder::*work)(), Progress &progress) {
  const Timer timer;
  (this->*work)();
  UVR_CUDA_CHECK(cudaGetLastError());
  UVR_CUDA_CHECK(cudaDeviceSynchronize()); // a fault in the step surfaces here
  stepMs_.emplace_back(name, timer.milliseconds());
  progress.advance(1);
}

void DeviceBuilder::centroids() {
  centroids_.resize(cells_);
  DeviceBuffer<AtomicBox> bounds;
  const AtomicBox empty = AtomicBox::empty();
  bounds.upload(&empty, 1);
  const unsigned blocks = std::min(cellBlocks(), 4096u); // each thread reduces several cells first
  centroidsKernel<<<blocks, kBlock>>>(mesh_, cells_, centroids_.data(), bounds.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  meshBounds_ = downloadOne(bounds.data()).box();
}

void DeviceBuilder::sortCells(const DeviceBuffer<uint32_t> &keys, int bits,
                              DeviceBuffer<uint32_t> &sortedKeys, DeviceBuffer<uint32_t> &order) {
  if (cellIndices_.size() != cells_) {
    cellIndices_.resize(cells_);
    indicesKernel<<<cellBlocks(), kBlock>>>(cells_, cellIndices_.data());
    UVR_CUDA_CHECK(cudaGetLastError());
  }
  sortedKeys.resize(cells_);
  order.resize(cells_);
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceRadixSort::SortPairs(storage, bytes, keys.data(), sortedKeys.data(),
                                           cellIndices_.data(), order.data(), int64_t(cells_), 0, bits);
  });
}

} // namespace gpu_build

std::vector<std::pair<std::string, double>> buildOnDevice(const MeshView &mesh, uint64_t pointCount,
                                                          uint32_t leafSize, DeviceAcceleration &out) {
  gpu_build::DeviceBuilder builder(mesh, pointCount, leafSize, out);
  builder.build();
  return builder.stepMs();
}

} // namespace uvr
