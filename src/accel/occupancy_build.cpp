#include "accel/occupancy.h"

#include "mesh/cell.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace uvr {
namespace {

// The four outward face planes of a tet, to tell voxels that cannot touch it.
struct TetPlanes {
  Vec3f normal[4];
  float offset[4];         // a point q is beyond face i when dot(normal[i], q) > offset[i]
  float inverseNormalX[4]; // 1 / normal[i].x, or 0 where that is 0

  bool set(const MeshView &mesh, uint64_t tet) {
    const uint32_t *v = mesh.tets + 4 * tet;
    const Vec3f p[4] = {mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]};
    for (int i = 0; i < 4; ++i) { // face i is the one opposite corner i
      const Vec3f a = p[(i + 1) % 4], b = p[(i + 2) % 4], c = p[(i + 3) % 4];
      Vec3f n = cross(b - a, c - a);
      if (dot(n, p[i] - a) > 0.f)
        n = n * -1.f;
      if (!(dot(n, n) > 0.f))
        return false; // degenerate: keep its whole box
      normal[i] = n;
      inverseNormalX[i] = n.x != 0.f ? 1.f / n.x : 0.f;
      // Padded by a relative epsilon so that rounding never clears a voxel the tet touches.
      offset[i] = dot(n, a) + 1e-4f * (fabsf(n.x) * (fabsf(a.x) + 1.f) + fabsf(n.y) * (fabsf(a.y) + 1.f) +
                                       fabsf(n.z) * (fabsf(a.z) + 1.f));
    }
    return true;
  }

  /// Narrows [first, last] to the voxels x of a row (voxel x spans [rowX + x * size.x, + size.x] at fixed y
  /// and z spans starting at rowY and rowZ) that lie beyond none of the face planes. A box lies beyond plane
  /// i when its corner nearest along the normal does; along the row that is one linear inequality in x.
  void clipRow(float rowX, float rowY, float rowZ, Vec3f size, float inverseSizeX, int &first,
               int &last) const {
    for (int i = 0; i < 4 && first <= last; ++i) {
      const Vec3f n = normal[i];
      const float nearY = n.y > 0.f ? rowY : rowY + size.y, nearZ = n.z > 0.f ? rowZ : rowZ + size.z;
      const float rest = offset[i] - n.y * nearY - n.z * nearZ; // the box is kept where n.x * nearX <= rest
      const float bound = (rest * inverseNormalX[i] - rowX) * inverseSizeX;
      const float lowest = float(first - 1), highest = float(last + 1); // keeps the casts below in range
      // nearX is rowX + x * size.x where n.x > 0, rowX + (x + 1) * size.x where n.x < 0.
      if (n.x > 0.f)
        last = std::min(last, int(std::floor(std::clamp(bound, lowest, highest))));
      else if (n.x < 0.f)
        first = std::max(first, int(std::ceil(std::clamp(bound - 1.f, lowest, highest))));
      else if (rest < 0.f)
        last = first - 1;
    }
  }
};

/// Sets bits [begin, end] of `bits`, which other threads set too.
void setBits(std::vector<uint64_t> &bits, uint64_t begin, uint64_t end) {
  for (uint64_t w = begin >> 6; w <= end >> 6; ++w) {
    uint64_t mask = ~uint64_t(0);
    if (w == begin >> 6)
      mask &= ~uint64_t(0) << (begin & 63);
    if (w == end >> 6)
      mask &= ~uint64_t(0) >> (63 - (end & 63));
    std::atomic_ref<uint64_t> word(bits[w]);
    if ((word.load(std::memory_order_relaxed) & mask) != mask)
      word.fetch_or(mask, std::memory_order_relaxed);
  }
}

void voxelRange(float lo, float hi, float origin, float scale, int count, int &first, int &last) {
  first = std::clamp(int(std::floor((lo - origin) * scale)), 0, count - 1);
  last = std::clamp(int(std::floor((hi - origin) * scale)), 0, count - 1);
}

} // namespace

OccupancyGrid buildOccupancyGrid(const MeshView &mesh, float voxelsPerCell) {
  OccupancyGrid grid;
  const uint64_t cells = mesh.cellCount();
  if (cells == 0)
    return grid;
  Box3f bounds;
  for (uint64_t c = 0; c < cells; ++c) // cheap next to the marking below, and exact
    bounds.extend(cellBounds(mesh, c));
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
  const uint64_t total = uint64_t(grid.nx) * uint64_t(grid.ny) * uint64_t(grid.nz);
  grid.bits.assign((total + 63) / 64, 0);

  const Vec3f voxelSize{size.x / float(grid.nx), size.y / float(grid.ny), size.z / float(grid.nz)};
  const float inverseVoxelX = 1.f / voxelSize.x;
  tbb::parallel_for(uint64_t(0), cells, [&](uint64_t c) {
    const Box3f box = cellBounds(mesh, c);
    int x0, x1, y0, y1, z0, z1;
    voxelRange(box.lower.x, box.upper.x, grid.origin.x, grid.voxelsPerUnit.x, grid.nx, x0, x1);
    voxelRange(box.lower.y, box.upper.y, grid.origin.y, grid.voxelsPerUnit.y, grid.ny, y0, y1);
    voxelRange(box.lower.z, box.upper.z, grid.origin.z, grid.voxelsPerUnit.z, grid.nz, z0, z1);
    // A tet fills a sixth of its box or less: voxels wholly beyond one of its face planes stay clear.
    TetPlanes planes{};
    const bool tet = c < mesh.tetCount && planes.set(mesh, c);
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y) {
        int first = x0, last = x1;
        if (tet)
          planes.clipRow(grid.origin.x, grid.origin.y + float(y) * voxelSize.y,
                         grid.origin.z + float(z) * voxelSize.z, voxelSize, inverseVoxelX, first, last);
        if (first > last)
          continue;
        const uint64_t row = (uint64_t(z) * uint64_t(grid.ny) + uint64_t(y)) * uint64_t(grid.nx);
        setBits(grid.bits, row + uint64_t(first), row + uint64_t(last));
      }
  });
  return grid;
}

} // namespace uvr
