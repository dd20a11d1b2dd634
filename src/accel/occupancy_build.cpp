#include "accel/occupancy.h"

#include "core/parallel_bounds.h"
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
};

/// Sets voxels [first, last] of row (y, z), whose bits other threads set too.
void setBits(OccupancyGrid &grid, int y, int z, int first, int last) {
  const uint64_t row = (uint64_t(z) * uint64_t(grid.ny) + uint64_t(y)) * uint64_t(grid.nx);
  const uint64_t begin = row + uint64_t(first), end = row + uint64_t(last);
  for (uint64_t w = begin >> 6; w <= end >> 6; ++w) {
    uint64_t mask = ~uint64_t(0);
    if (w == begin >> 6)
      mask &= ~uint64_t(0) << (begin & 63);
    if (w == end >> 6)
      mask &= ~uint64_t(0) >> (63 - (end & 63));
    std::atomic_ref<uint64_t> word(grid.bits[w]);
    if ((word.load(std::memory_order_relaxed) & mask) != mask)
      word.fetch_or(mask, std::memory_order_relaxed);
  }
}

void voxelRange(float lo, float hi, float origin, float scale, int count, int &first, int &last) {
  first = std::clamp(int(std::floor((lo - origin) * scale)), 0, count - 1);
  last = std::clamp(int(std::floor((hi - origin) * scale)), 0, count - 1);
}

/// Voxel index ranges, inclusive, of a cell's box.
struct VoxelRange {
  int x0, x1, y0, y1, z0, z1;
};

int floorToInt(float v) {
  const int truncated = int(v);
  return truncated - int(float(truncated) > v);
}

int ceilToInt(float v) {
  const int truncated = int(v);
  return truncated + int(float(truncated) < v);
}

/// Sets the voxels of `range` that lie beyond none of the tet's face planes. A voxel lies beyond plane i
/// when its corner nearest along the normal does; along a row of voxels in x (voxel x spans
/// [origin.x + x * size.x, + size.x]) that is one linear inequality in x, which narrows the row's span. Rows
/// go a batch at a time, one plane after the other, so that the compiler vectorises across rows (2x faster
/// than a row at a time); the loops over a batch stay rolled, since GCC leaves them scalar once it has
/// unrolled them. The terms that depend on y alone are computed once per batch of rows.
void markTet(const TetPlanes &planes, const VoxelRange &range, Vec3f voxelSize, OccupancyGrid &grid) {
  constexpr int kBatch = 8;
  const Vec3f origin = grid.origin;
  const float inverseSizeX = 1.f / voxelSize.x;
  // Clamped bounds keep the casts in range; one voxel past the range is enough to clear a row.
  const float lowest = float(range.x0 - 1), highest = float(range.x1 + 1);
  for (int batchY = range.y0; batchY <= range.y1; batchY += kBatch) {
    float restY[4][kBatch]; // offset[i] - n.y * nearY, nearY being the row's y nearest along the normal
    for (int i = 0; i < 4; ++i) {
      const float normalY = planes.normal[i].y;
#pragma GCC unroll 1
      for (int r = 0; r < kBatch; ++r) {
        const float rowY = origin.y + float(batchY + r) * voxelSize.y;
        restY[i][r] = planes.offset[i] - normalY * (normalY > 0.f ? rowY : rowY + voxelSize.y);
      }
    }
    const int rows = std::min(kBatch, range.y1 - batchY + 1);
    for (int z = range.z0; z <= range.z1; ++z) {
      const float sliceZ = origin.z + float(z) * voxelSize.z;
      int first[kBatch], last[kBatch];
      std::fill_n(first, kBatch, range.x0);
      std::fill_n(last, kBatch, range.x1);
      for (int i = 0; i < 4; ++i) {
        const Vec3f n = planes.normal[i];
        const float zTerm = n.z * (n.z > 0.f ? sliceZ : sliceZ + voxelSize.z);
        const float inverseNormalX = planes.inverseNormalX[i];
        float bound[kBatch]; // a voxel is kept where n.x * nearX <= rest, i.e. nearX on the bound's side
#pragma GCC unroll 1
        for (int r = 0; r < kBatch; ++r)
          bound[r] = ((restY[i][r] - zTerm) * inverseNormalX - origin.x) * inverseSizeX;
        if (n.x > 0.f) { // nearX is the voxel's lower x
#pragma GCC unroll 1
          for (int r = 0; r < kBatch; ++r)
            last[r] = std::min(last[r], floorToInt(clampf(bound[r], lowest, highest)));
        } else if (n.x < 0.f) { // nearX is its upper x, one voxel further
#pragma GCC unroll 1
          for (int r = 0; r < kBatch; ++r)
            first[r] = std::max(first[r], ceilToInt(clampf(bound[r] - 1.f, lowest, highest)));
        } else {
#pragma GCC unroll 1
          for (int r = 0; r < kBatch; ++r)
            last[r] = restY[i][r] - zTerm < 0.f ? range.x0 - 1 : last[r];
        }
      }
      for (int r = 0; r < rows; ++r)
        if (first[r] <= last[r])
          setBits(grid, batchY + r, z, first[r], last[r]);
    }
  }
}

} // namespace

OccupancyGrid buildOccupancyGrid(const MeshView &mesh, float voxelsPerCell) {
  OccupancyGrid grid;
  const uint64_t cells = mesh.cellCount();
  if (cells == 0)
    return grid;
  const Box3f bounds = parallelBounds(cells, [&](uint64_t c) { return cellBounds(mesh, c); });
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
  tbb::parallel_for(uint64_t(0), cells, [&](uint64_t c) {
    const Box3f box = cellBounds(mesh, c);
    VoxelRange range;
    voxelRange(box.lower.x, box.upper.x, grid.origin.x, grid.voxelsPerUnit.x, grid.nx, range.x0, range.x1);
    voxelRange(box.lower.y, box.upper.y, grid.origin.y, grid.voxelsPerUnit.y, grid.ny, range.y0, range.y1);
    voxelRange(box.lower.z, box.upper.z, grid.origin.z, grid.voxelsPerUnit.z, grid.nz, range.z0, range.z1);
    // A tet fills a sixth of its box or less: voxels wholly beyond one of its face planes stay clear.
    TetPlanes planes;
    if (c < mesh.tetCount && planes.set(mesh, c)) {
      markTet(planes, range, voxelSize, grid);
      return;
    }
    for (int z = range.z0; z <= range.z1; ++z)
      for (int y = range.y0; y <= range.y1; ++y)
        setBits(grid, y, z, range.x0, range.x1);
  });
  return grid;
}

} // namespace uvr
