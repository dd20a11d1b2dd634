// The GPU's twin of accel/seed_grid_build.cpp: each voxel's seed cell, and the boundary faces per voxel in
// compressed rows.
#include "backend/cuda/device_builder.cuh"

#include "mesh/cell.h"

#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>

namespace uvr::gpu_build {
namespace {

__global__ void seedKernel(MeshView mesh, uint64_t cells, VoxelGrid grid, uint32_t *seeds) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  forEachSeededVoxel(mesh, c, grid, [&](uint64_t voxel) { atomicMin(seeds + voxel, uint32_t(c)); });
}

/// Per boundary face of the tets, per voxel it meets: counts the face there (`faces` null), or puts it and
/// the octants it meets in the voxel's next free slot (`slots`, advanced; the row's order is arbitrary).
__global__ void boundaryFacesKernel(MeshView mesh, const uint32_t *tetNeighbors, VoxelGrid grid,
                                    uint32_t *slots, uint32_t *faces, uint8_t *octants) {
  const uint64_t entry = globalIndex();
  if (entry >= 4 * mesh.tetCount || tetNeighbors[entry] != kNoCell)
    return;
  forEachBoundaryVoxel(mesh, uint32_t(entry), grid, [&](uint64_t voxel, uint32_t faceOctants) {
    const uint32_t slot = atomicAdd(slots + voxel, 1u);
    if (faces) {
      faces[slot] = uint32_t(entry);
      octants[slot] = uint8_t(faceOctants);
    }
  });
}

} // namespace

void DeviceBuilder::seeds() {
  out_.seeds.grid = placeVoxelGrid(meshBounds_, cells_, kDefaultSeedVoxelsPerCell);
  out_.seeds.seeds.resize(out_.seeds.grid.voxelCount());
  UVR_CUDA_CHECK(cudaMemset(out_.seeds.seeds.data(), 0xff, out_.seeds.seeds.bytes())); // kNoCell
  seedKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, out_.seeds.grid, out_.seeds.seeds.data());
  if (listsBoundaryFaces(mesh_))
    boundaryFaces();
}

void DeviceBuilder::boundaryFaces() {
  const uint64_t voxels = out_.seeds.seeds.size(), entries = 4 * mesh_.tetCount;
  DeviceBuffer<uint32_t> slots;
  slots.resize(voxels + 1);
  UVR_CUDA_CHECK(cudaMemset(slots.data(), 0, slots.bytes()));
  boundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(
      mesh_, out_.tetNeighbors.data(), out_.seeds.grid, slots.data(), nullptr, nullptr);
  UVR_CUDA_CHECK(cudaGetLastError());
  // Summed in 64 bits: past 2^32 - 1 entries the rows cannot be numbered, and the grid lists none.
  DeviceBuffer<unsigned long long> total;
  total.resize(1);
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceReduce::Sum(storage, bytes, slots.data(), total.data(), int64_t(voxels));
  });
  if (downloadOne(total.data()) > UINT32_MAX)
    return;
  out_.seeds.boundaryStart.resize(voxels + 1);
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceScan::ExclusiveSum(storage, bytes, slots.data(), out_.seeds.boundaryStart.data(),
                                         int64_t(voxels + 1));
  });
  out_.seeds.boundaryFaces.resize(downloadOne(out_.seeds.boundaryStart.data() + voxels));
  out_.seeds.boundaryOctants.resize(out_.seeds.boundaryFaces.size());
  UVR_CUDA_CHECK(
      cudaMemcpy(slots.data(), out_.seeds.boundaryStart.data(), slots.bytes(), cudaMemcpyDeviceToDevice));
  boundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(
      mesh_, out_.tetNeighbors.data(), out_.seeds.grid, slots.data(), out_.seeds.boundaryFaces.data(),
      out_.seeds.boundaryOctants.data());
}

} // namespace uvr::gpu_build
