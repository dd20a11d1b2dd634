// The GPU build's steps run in order (the steps themselves: see device_builder.cuh), with the cell centroids
// and the mesh's box that the later steps start from, and the cell sort that the BVH and the partitions
// share.
#include "backend/cuda/device_builder.cuh"

#include "mesh/cell.h"
#include <uvr/system.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/util_type.cuh>

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

/// The mesh's box, reduced warp by warp into `bounds`.
__global__ void boundsKernel(MeshView mesh, uint64_t cells, AtomicBox *bounds) {
  Box3f local;
  for (uint64_t c = globalIndex(); c < cells; c += uint64_t(gridDim.x) * blockDim.x)
    local.extend(cellBounds(mesh, c));
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
  Progress progress("building acceleration on the GPU", lean_ ? 4 : 7);
  // The step keeps its name from when the centroids were kept: it finds the mesh's box from the cells'.
  step("cell centroids", &DeviceBuilder::bounds, progress);
  step("partitions", &DeviceBuilder::partitions, progress);
  if (!lean_)
    step("tet adjacency", &DeviceBuilder::tetAdjacency, progress);
  step("point-location hierarchy", &DeviceBuilder::bvh, progress);
  step("occupancy grid", &DeviceBuilder::occupancy, progress);
  if (!lean_) {
    step("seed grid", &DeviceBuilder::seeds, progress);
    step("boundary faces", &DeviceBuilder::boundaryFaceList, progress);
  }
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

void DeviceBuilder::bounds() {
  DeviceBuffer<AtomicBox> bounds;
  const AtomicBox empty = AtomicBox::empty();
  bounds.upload(&empty, 1);
  const unsigned blocks = std::min(cellBlocks(), 4096u); // each thread reduces several cells first
  boundsKernel<<<blocks, kBlock>>>(mesh_, cells_, bounds.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  meshBounds_ = downloadOne(bounds.data()).box();
}

void DeviceBuilder::identityOrder(DeviceBuffer<uint32_t> &order) {
  order.resize(cells_);
  indicesKernel<<<cellBlocks(), kBlock>>>(cells_, order.data());
  UVR_CUDA_CHECK(cudaGetLastError());
}

void DeviceBuilder::sortByDigit(DeviceBuffer<uint8_t> &digits, DeviceBuffer<uint8_t> &digitsOther,
                                DeviceBuffer<uint32_t> &order, DeviceBuffer<uint32_t> &orderOther) {
  cub::DoubleBuffer<uint8_t> sortedDigits(digits.data(), digitsOther.data());
  cub::DoubleBuffer<uint32_t> sortedOrder(order.data(), orderOther.data());
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceRadixSort::SortPairs(storage, bytes, sortedDigits, sortedOrder, int64_t(cells_), 0, 8);
  });
  if (sortedDigits.Current() != digits.data())
    digits.swap(digitsOther);
  if (sortedOrder.Current() != order.data())
    order.swap(orderOther);
}

void DeviceBuilder::sortCells(DeviceBuffer<uint32_t> &keys, int bits, DeviceBuffer<uint32_t> &order) {
  identityOrder(order);
  DeviceBuffer<uint32_t> keysOther, orderOther;
  keysOther.resize(cells_);
  orderOther.resize(cells_);
  cub::DoubleBuffer<uint32_t> sortedKeys(keys.data(), keysOther.data()),
      sortedOrder(order.data(), orderOther.data());
  // A stable sort of the indices in order: ties stay by index.
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceRadixSort::SortPairs(storage, bytes, sortedKeys, sortedOrder, int64_t(cells_), 0, bits);
  });
  if (sortedKeys.Current() != keys.data())
    keys.swap(keysOther);
  if (sortedOrder.Current() != order.data())
    order.swap(orderOther);
}

} // namespace gpu_build

std::vector<std::pair<std::string, double>> buildOnDevice(const MeshView &mesh, uint64_t pointCount,
                                                          uint32_t leafSize, bool lean,
                                                          DeviceAcceleration &out) {
  gpu_build::DeviceBuilder builder(mesh, pointCount, leafSize, lean, out);
  builder.build();
  return builder.stepMs();
}

} // namespace uvr
