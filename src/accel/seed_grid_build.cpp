#include "accel/seed_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cstdint>

namespace uvr {

namespace {

/// Compressed rows of the boundary faces per voxel: counted, offset by a scan, then filled.
void listBoundaryFaces(const MeshView &mesh, const uint32_t *tetNeighbors, SeedGrid &grid) {
  auto forEachBoundaryFace = [&](auto &&visit) {
    tbb::parallel_for(uint64_t(0), mesh.tetCount, [&](uint64_t t) {
      for (uint32_t i = 0; i < 4; ++i)
        if (tetNeighbors[4 * t + i] == kNoCell)
          forEachBoundaryVoxel(mesh, uint32_t(4 * t + i), grid.grid,
                               [&](uint64_t voxel, uint32_t octants) { visit(voxel, 4 * t + i, octants); });
    });
  };
  std::vector<uint32_t> counts(grid.grid.voxelCount(), 0);
  forEachBoundaryFace([&](uint64_t voxel, uint64_t, uint32_t) {
    std::atomic_ref<uint32_t>(counts[voxel]).fetch_add(1, std::memory_order_relaxed);
  });
  std::vector<uint32_t> start(counts.size() + 1);
  uint64_t total = 0;
  for (size_t v = 0; v < counts.size(); ++v) {
    start[v] = uint32_t(total);
    total += counts[v];
    if (total > UINT32_MAX)
      return; // too many to number in 32 bits: no lists, every such sample goes to the BVH
  }
  start.back() = uint32_t(total);
  std::vector<uint32_t> faces(total);
  std::vector<uint8_t> octants(total);
  std::copy(start.begin(), start.end() - 1, counts.begin()); // each voxel's next free slot
  forEachBoundaryFace([&](uint64_t voxel, uint64_t face, uint32_t faceOctants) {
    const uint32_t slot = std::atomic_ref<uint32_t>(counts[voxel]).fetch_add(1, std::memory_order_relaxed);
    faces[slot] = uint32_t(face);
    octants[slot] = uint8_t(faceOctants);
  });
  grid.boundaryStart = std::move(start);
  grid.boundaryFaces = std::move(faces);
  grid.boundaryOctants = std::move(octants);
}

} // namespace

SeedGrid buildSeedGrid(const MeshView &mesh, const uint32_t *tetNeighbors, float voxelsPerCell) {
  const uint64_t cells = mesh.cellCount();
  if (cells == 0)
    return {};
  SeedGrid grid;
  grid.grid = placeVoxelGrid(mesh, voxelsPerCell);
  grid.seeds.assign(grid.grid.voxelCount(), kNoCell);
  tbb::parallel_for(uint64_t(0), cells, [&](uint64_t c) {
    forEachSeededVoxel(mesh, c, grid.grid, [&](uint64_t voxel) {
      // A centre on a shared face lies in several cells: the lowest-numbered one wins.
      std::atomic_ref<uint32_t> seed(grid.seeds[voxel]);
      uint32_t current = seed.load(std::memory_order_relaxed);
      while (uint32_t(c) < current &&
             !seed.compare_exchange_weak(current, uint32_t(c), std::memory_order_relaxed))
        ;
    });
  });
  if (tetNeighbors && listsBoundaryFaces(mesh))
    listBoundaryFaces(mesh, tetNeighbors, grid);
  return grid;
}

} // namespace uvr
