#include "accel/occupancy_build.h"

#include <tbb/parallel_for.h>

#include <atomic>

namespace uvr {

OccupancyGrid buildOccupancyGrid(const MeshView &mesh, float voxelsPerCell) {
  const uint64_t cells = mesh.cellCount();
  if (cells == 0)
    return {};
  OccupancyGrid grid;
  grid.grid = placeVoxelGrid(mesh, voxelsPerCell);
  grid.bits.assign(grid.wordCount(), 0);
  tbb::parallel_for(uint64_t(0), cells, [&](uint64_t c) {
    markCell(mesh, c, grid.grid, [&](uint64_t w, uint64_t mask) {
      std::atomic_ref<uint64_t> word(grid.bits[w]); // other threads set bits of the same word
      if ((word.load(std::memory_order_relaxed) & mask) != mask)
        word.fetch_or(mask, std::memory_order_relaxed);
    });
  });
  return grid;
}

} // namespace uvr
