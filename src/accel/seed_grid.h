// Where point location starts for a sample far from the last one: per voxel of a coarse grid over the mesh
// bounds, a cell holding the voxel's centre. A walk from the previous sample's cell crosses every cell in
// between, so with steps of many cells (adaptive sampling) it would cost as much as the samples it saves;
// from the seed it crosses a cell or two wherever the sample lies. Flat arrays, usable on host and device.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// A walk from a seed crosses a cell or two; a few more leave room for slivers.
constexpr int kSeedWalkSteps = 8;

struct SeedGridView {
  const uint32_t *seeds = nullptr; ///< per voxel, x fastest; kNoCell where no cell holds the centre
  Vec3f origin;
  Vec3f voxelsPerUnit;
  int nx = 0, ny = 0, nz = 0;
  float voxelEdge = 0.f; ///< the longest side of a voxel

  /// The seed of the voxel holding `p`, or kNoCell (also outside the grid, and without a grid).
  UVR_HOST_DEVICE uint32_t seedAt(Vec3f p) const {
    if (!seeds)
      return kNoCell;
    const float fx = (p.x - origin.x) * voxelsPerUnit.x, fy = (p.y - origin.y) * voxelsPerUnit.y,
                fz = (p.z - origin.z) * voxelsPerUnit.z;
    if (!(fx >= 0.f && fy >= 0.f && fz >= 0.f)) // also rejects NaN
      return kNoCell;
    const int x = int(fx), y = int(fy), z = int(fz);
    if (x >= nx || y >= ny || z >= nz)
      return kNoCell;
    return seeds[(uint64_t(z) * uint64_t(ny) + uint64_t(y)) * uint64_t(nx) + uint64_t(x)];
  }
};

struct SeedGrid {
  std::vector<uint32_t> seeds;
  Vec3f origin, voxelsPerUnit;
  Vec3f voxelSize; ///< the extent over the voxel count, per axis
  int nx = 0, ny = 0, nz = 0;

  SeedGridView view() const {
    return {
        seeds.data(), origin, voxelsPerUnit, nx, ny, nz, maxf(voxelSize.x, maxf(voxelSize.y, voxelSize.z))};
  }
  uint64_t voxelCount() const { return uint64_t(nx) * uint64_t(ny) * uint64_t(nz); }
  size_t memoryBytes() const { return seeds.size() * sizeof(uint32_t); }
};

/// About `voxelsPerCell` voxels per cell over the mesh bounds, 4 bytes each. The default keeps a walk from a
/// seed to a few cells on the brain meshes, whose cells fill about half their bounds.
constexpr float kDefaultSeedVoxelsPerCell = 0.5f;

/// The grid with its seeds: each voxel's is the lowest-numbered cell holding its centre, so that any build
/// order gives the same grid.
SeedGrid buildSeedGrid(const MeshView &mesh, float voxelsPerCell = kDefaultSeedVoxelsPerCell);

/// The grid's placement and shape for a mesh of `cells` cells within `bounds`; no seeds allocated.
SeedGrid seedGridShape(const Box3f &bounds, uint64_t cells, float voxelsPerCell);

/// Calls `offer(voxel)` for each voxel of `grid` whose centre lies in cell `c`.
template <typename Offer>
UVR_HOST_DEVICE void forEachSeededVoxel(const MeshView &mesh, uint64_t c, const SeedGridView &grid,
                                        Vec3f voxelSize, Offer &&offer) {
  const Box3f box = cellBounds(mesh, c);
  // Voxel i's centre is origin + (i + 1/2) * size: the indices whose centres lie within the box, with a
  // hundredth of a voxel's slack against rounding (the test below is exact).
  auto span = [](float lo, float hi, float origin, float scale, int count, int &first, int &last) {
    first = int(ceilf((lo - origin) * scale - 0.51f));
    last = int(floorf((hi - origin) * scale - 0.49f));
    first = first < 0 ? 0 : first;
    last = last > count - 1 ? count - 1 : last;
  };
  int x0, x1, y0, y1, z0, z1;
  span(box.lower.x, box.upper.x, grid.origin.x, grid.voxelsPerUnit.x, grid.nx, x0, x1);
  span(box.lower.y, box.upper.y, grid.origin.y, grid.voxelsPerUnit.y, grid.ny, y0, y1);
  span(box.lower.z, box.upper.z, grid.origin.z, grid.voxelsPerUnit.z, grid.nz, z0, z1);
  for (int z = z0; z <= z1; ++z)
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Vec3f centre{grid.origin.x + (float(x) + 0.5f) * voxelSize.x,
                           grid.origin.y + (float(y) + 0.5f) * voxelSize.y,
                           grid.origin.z + (float(z) + 0.5f) * voxelSize.z};
        if (cellContains(mesh, c, centre))
          offer((uint64_t(z) * uint64_t(grid.ny) + uint64_t(y)) * uint64_t(grid.nx) + uint64_t(x));
      }
}

} // namespace uvr
