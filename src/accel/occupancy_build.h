// How the occupancy grid is built, cell by cell: the host's build and the GPU's share these functions, so
// that both set the same bits.
#pragma once

#include "accel/occupancy.h"
#include "core/host_device.h"
#include "mesh/cell.h"

#include <cstdint>

// Keeps GCC from unrolling a loop it then leaves scalar (see markTet); nvcc's passes see no pragma.
#if defined(__CUDACC__)
#define UVR_NO_UNROLL
#else
#define UVR_NO_UNROLL _Pragma("GCC unroll 1")
#endif

namespace uvr {

// The four outward face planes of a tet, to tell voxels that cannot touch it.
struct TetPlanes {
  Vec3f normal[4];
  float offset[4];         // a point q is beyond face i when dot(normal[i], q) > offset[i]
  float inverseNormalX[4]; // 1 / normal[i].x, or 0 where that is 0

  UVR_HOST_DEVICE bool set(const MeshView &mesh, uint64_t tet) {
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

/// Voxel index ranges, inclusive, of a cell's box.
struct VoxelRange {
  int x0, x1, y0, y1, z0, z1;
};

UVR_HOST_DEVICE inline int floorToInt(float v) {
  const int truncated = int(v);
  return truncated - int(float(truncated) > v);
}

UVR_HOST_DEVICE inline int ceilToInt(float v) {
  const int truncated = int(v);
  return truncated + int(float(truncated) < v);
}

UVR_HOST_DEVICE inline void voxelSpan(float lo, float hi, float origin, float scale, int count, int &first,
                                      int &last) {
  auto clampIndex = [count](int i) { return i < 0 ? 0 : (i > count - 1 ? count - 1 : i); };
  first = clampIndex(int(floorf((lo - origin) * scale)));
  last = clampIndex(int(floorf((hi - origin) * scale)));
}

/// Calls `setRow(y, z, first, last)` for the voxels [first, last] of each row (y, z) that lie beyond none of
/// the tet's face planes. A voxel lies beyond plane i when its corner nearest along the normal does; along a
/// row of voxels in x (voxel x spans [origin.x + x * size.x, + size.x]) that is one linear inequality in x,
/// which narrows the row's span. Rows go a batch at a time, one plane after the other, so that the compiler
/// vectorises across rows; the loops over a batch stay rolled, since GCC
/// leaves them scalar once it has unrolled them. The terms that depend on y alone are computed once per
/// batch of rows.
template <typename SetRow>
UVR_HOST_DEVICE void markTet(const TetPlanes &planes, const VoxelRange &range, Vec3f origin, Vec3f voxelSize,
                             SetRow &&setRow) {
  constexpr int kBatch = 8;
  const float inverseSizeX = 1.f / voxelSize.x;
  // Clamped bounds keep the casts in range; one voxel past the range is enough to clear a row.
  const float lowest = float(range.x0 - 1), highest = float(range.x1 + 1);
  for (int batchY = range.y0; batchY <= range.y1; batchY += kBatch) {
    float restY[4][kBatch]; // offset[i] - n.y * nearY, nearY being the row's y nearest along the normal
    for (int i = 0; i < 4; ++i) {
      const float normalY = planes.normal[i].y;
      UVR_NO_UNROLL
      for (int r = 0; r < kBatch; ++r) {
        const float rowY = origin.y + float(batchY + r) * voxelSize.y;
        restY[i][r] = planes.offset[i] - normalY * (normalY > 0.f ? rowY : rowY + voxelSize.y);
      }
    }
    const int rows = range.y1 - batchY + 1 < kBatch ? range.y1 - batchY + 1 : kBatch;
    for (int z = range.z0; z <= range.z1; ++z) {
      const float sliceZ = origin.z + float(z) * voxelSize.z;
      int first[kBatch], last[kBatch];
      for (int r = 0; r < kBatch; ++r) {
        first[r] = range.x0;
        last[r] = range.x1;
      }
      for (int i = 0; i < 4; ++i) {
        const Vec3f n = planes.normal[i];
        const float zTerm = n.z * (n.z > 0.f ? sliceZ : sliceZ + voxelSize.z);
        const float inverseNormalX = planes.inverseNormalX[i];
        float bound[kBatch]; // a voxel is kept where n.x * nearX <= rest, i.e. nearX on the bound's side
        UVR_NO_UNROLL
        for (int r = 0; r < kBatch; ++r)
          bound[r] = ((restY[i][r] - zTerm) * inverseNormalX - origin.x) * inverseSizeX;
        if (n.x > 0.f) { // nearX is the voxel's lower x
          UVR_NO_UNROLL
          for (int r = 0; r < kBatch; ++r) {
            const int x = floorToInt(clampf(bound[r], lowest, highest));
            last[r] = x < last[r] ? x : last[r];
          }
        } else if (n.x < 0.f) { // nearX is its upper x, one voxel further
          UVR_NO_UNROLL
          for (int r = 0; r < kBatch; ++r) {
            const int x = ceilToInt(clampf(bound[r] - 1.f, lowest, highest));
            first[r] = x > first[r] ? x : first[r];
          }
        } else {
          UVR_NO_UNROLL
          for (int r = 0; r < kBatch; ++r)
            last[r] = restY[i][r] - zTerm < 0.f ? range.x0 - 1 : last[r];
        }
      }
      for (int r = 0; r < rows; ++r)
        if (first[r] <= last[r])
          setRow(batchY + r, z, first[r], last[r]);
    }
  }
}

/// Calls `setWord(index, mask)` for the bits of `grid` that cell `c` may reach: the voxels its box touches,
/// less those wholly beyond a face plane of a tet.
template <typename SetWord>
UVR_HOST_DEVICE void markCell(const MeshView &mesh, uint64_t c, const VoxelGrid &grid, SetWord &&setWord) {
  auto setRow = [&](int y, int z, int first, int last) {
    const uint64_t row = (uint64_t(z) * uint64_t(grid.ny) + uint64_t(y)) * uint64_t(grid.nx);
    const uint64_t begin = row + uint64_t(first), end = row + uint64_t(last);
    for (uint64_t w = begin >> 6; w <= end >> 6; ++w) {
      uint64_t mask = ~uint64_t(0);
      if (w == begin >> 6)
        mask &= ~uint64_t(0) << (begin & 63);
      if (w == end >> 6)
        mask &= ~uint64_t(0) >> (63 - (end & 63));
      setWord(w, mask);
    }
  };
  const Box3f box = cellBounds(mesh, c);
  VoxelRange range;
  voxelSpan(box.lower.x, box.upper.x, grid.origin.x, grid.voxelsPerUnit.x, grid.nx, range.x0, range.x1);
  voxelSpan(box.lower.y, box.upper.y, grid.origin.y, grid.voxelsPerUnit.y, grid.ny, range.y0, range.y1);
  voxelSpan(box.lower.z, box.upper.z, grid.origin.z, grid.voxelsPerUnit.z, grid.nz, range.z0, range.z1);
  // A tet fills a sixth of its box or less: voxels wholly beyond one of its face planes stay clear.
  TetPlanes planes;
  if (c < mesh.tetCount && planes.set(mesh, c)) {
    markTet(planes, range, grid.origin, grid.voxelSize, setRow);
    return;
  }
  for (int z = range.z0; z <= range.z1; ++z)
    for (int y = range.y0; y <= range.y1; ++y)
      setRow(y, z, range.x0, range.x1);
}

} // namespace uvr
