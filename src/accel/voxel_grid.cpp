#include "accel/voxel_grid.h"
#include "core/parallel_bounds.h"
#include "mesh/cell.h"

#include <algorithm>
#include <cmath>

namespace uvr {

VoxelGrid placeVoxelGrid(const Box3f &bounds, uint64_t cells, float voxelsPerCell) {
  VoxelGrid grid;
  const Vec3f size = bounds.size();
  const double volume = std::max(double(size.x) * size.y * size.z, 1e-30);
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

VoxelGrid placeVoxelGrid(const MeshView &mesh, float voxelsPerCell) {
  const uint64_t cells = mesh.cellCount();
  return placeVoxelGrid(parallelBounds(cells, [&](uint64_t c) { return cellBounds(mesh, c); }), cells,
                        voxelsPerCell);
}

} // namespace uvr
