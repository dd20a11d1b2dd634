#include "accel/occupancy_build.h"
#include "accel/seed_grid.h"
#include "core/parallel_bounds.h"

#include <tbb/parallel_for.h>

#include <atomic>

namespace uvr {

SeedGrid seedGridShape(const Box3f &bounds, uint64_t cells, float voxelsPerCell) {
  const OccupancyGrid shape = occupancyShape(bounds, cells, voxelsPerCell); // placed as the occupancy grid
  SeedGrid grid;
  grid.origin = shape.origin;
  grid.voxelsPerUnit = shape.voxelsPerUnit;
  grid.voxelSize = shape.voxelSize;
  grid.nx = shape.nx;
  grid.ny = shape.ny;
  grid.nz = shape.nz;
  return grid;
}

SeedGrid buildSeedGrid(const MeshView &mesh, float voxelsPerCell) {
  const uint64_t cells = mesh.cellCount();
  if (cells == 0)
    return {};
  SeedGrid grid = seedGridShape(parallelBounds(cells, [&](uint64_t c) { return cellBounds(mesh, c); }), cells,
                                voxelsPerCell);
  grid.seeds.assign(grid.voxelCount(), kNoCell);
  const SeedGridView view = grid.view();
  tbb::parallel_for(uint64_t(0), cells, [&](uint64_t c) {
    forEachSeededVoxel(mesh, c, view, grid.voxelSize, [&](uint64_t voxel) {
      // A centre on a shared face lies in several cells: the lowest-numbered one wins.
      std::atomic_ref<uint32_t> seed(grid.seeds[voxel]);
      uint32_t current = seed.load(std::memory_order_relaxed);
      while (uint32_t(c) < current &&
             !seed.compare_exchange_weak(current, uint32_t(c), std::memory_order_relaxed))
        ;
    });
  });
  return grid;
}

} // namespace uvr
