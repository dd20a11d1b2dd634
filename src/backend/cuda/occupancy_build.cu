// The GPU's twin of accel/occupancy_build.cpp: every cell marks its voxels with the host's markCell.
#include "backend/cuda/device_builder.cuh"

#include "accel/occupancy_build.h"

namespace uvr::gpu_build {
namespace {

__global__ void occupancyKernel(MeshView mesh, uint64_t cells, VoxelGrid grid, unsigned long long *bits) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  markCell(mesh, c, grid, [&](uint64_t w, uint64_t mask) {
    if ((bits[w] & mask) != mask)
      atomicOr(bits + w, (unsigned long long)mask);
  });
}

} // namespace

void DeviceBuilder::occupancy() {
  OccupancyBits<DeviceStorage> &grid = out_.occupancy;
  grid.grid = placeVoxelGrid(meshBounds_, cells_, kDefaultVoxelsPerCell);
  grid.bits.resize(grid.wordCount());
  UVR_CUDA_CHECK(cudaMemset(grid.bits.data(), 0, grid.bits.bytes()));
  occupancyKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, grid.grid,
                                            reinterpret_cast<unsigned long long *>(grid.bits.data()));
}

} // namespace uvr::gpu_build
