#include "accel/occupancy_build.h"

#include "core/parallel_bounds.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace uvr {

OccupancyGrid occupancyShape(const Box3f &bounds, uint64_t cells, float voxelsPerCell) {
  OccupancyGrid grid;
  const Vec3f size = bounds.size();
  const double volume = std::max(double(size.x) * size.y * size.z, 1e-30);
  // Cubic voxels; the count is capped so that the grid stays a small fraction of the mesh's memory.
  const double voxels = std::min(double(voxelsPerCell) * double(cells), double(1ull << 33));
  const double edge = std::cbrt(volume / voxels);
  auto axisCount = [&](float extent) { return std::clamp(int(std::ceil(extent / edge)), 1, 1 << 20); };
  grid.nx = axisCount(size.x);
  grid.ny = axisCount(size.y);
  grid.nz = axisCount(size.z);
  grid.origin = bounds.lower;
  // Voxels span the exact extent per axis, so that the upper bound maps to the last voxel, not past it.
  grid.voxelsPerUnit = {size.x > 0.f ? float(grid.nx) / size.x : 0.f,
                        size.y > 0.f ? float(grid.ny) / size.y : 0.f,
                        size.z > 0.f ? float(grid.nz) / size.z : 0.f};
  grid.voxelSize = {size.x / float(grid.nx), size.y / float(grid.ny), size.z / float(grid.nz)};
  return grid;
}

OccupancyGrid buildOccupancyGrid(const MeshView &mesh, float voxelsPerCell) {
  const uint64_t cells = mesh.cellCount();
  if (cells == 0)
    return {};
  OccupancyGrid grid = occupancyShape(parallelBounds(cells, [&](uint64_t c) { return cellBounds(mesh, c); }),
                                      cells, voxelsPerCell);
  grid.bits.assign(grid.wordCount(), 0);
  const OccupancyView view = grid.view();
  tbb::parallel_for(uint64_t(0), cells, [&](uint64_t c) {
    markCell(mesh, c, view, grid.voxelSize, [&](uint64_t w, uint64_t mask) {
      std::atomic_ref<uint64_t> word(grid.bits[w]); // other threads set bits of the same word
      if ((word.load(std::memory_order_relaxed) & mask) != mask)
        word.fetch_or(mask, std::memory_order_relaxed);
    });
  });
  return grid;
}

} // namespace uvr
