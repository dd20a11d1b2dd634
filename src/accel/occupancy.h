// A bit per voxel of a grid over the mesh bounds, set where some cell's box reaches: most samples that fall
// in no cell (empty space inside the bounds, concavities of the mesh) are rejected by one load instead of a
// failed walk and a failed BVH query. Flat arrays, usable on host and device.
#pragma once

#include "accel/voxel_grid.h"
#include "core/host_device.h"
#include "core/storage.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

struct OccupancyView {
  const uint64_t *bits = nullptr; ///< null: every point may lie in a cell
  VoxelGrid grid;

  /// False only where no cell can hold `p`.
  UVR_HOST_DEVICE bool mayHoldCell(Vec3f p) const {
    if (!bits)
      return true;
    int x, y, z;
    if (!grid.voxelOf(p, x, y, z))
      return false;
    const uint64_t voxel = grid.index(x, y, z);
    return (bits[voxel >> 6] >> (voxel & 63)) & 1u;
  }
  UVR_HOST_DEVICE uint64_t wordCount() const { return (grid.voxelCount() + 63) / 64; }
};

template <typename Storage> struct OccupancyBits {
  typename Storage::template Array<uint64_t> bits;
  VoxelGrid grid;

  OccupancyView view() const { return {bits.data(), grid}; }
  uint64_t wordCount() const { return view().wordCount(); }
  template <typename A, typename B, typename F> static void forEachMember(A &a, B &b, F &&f) {
    f(a.bits, b.bits);
    f(a.grid, b.grid);
  }
};
using OccupancyGrid = OccupancyBits<HostStorage>;

/// About `voxelsPerCell` voxels per cell over the mesh bounds (a bit each), set where a cell may reach (its
/// box; for a tet, the part of its box its face planes do not exclude). A fine grid leaves fewer samples near
/// the surface to a BVH query that finds nothing, for 2 bytes per cell and a longer build (the default's
/// measurements: docs/results/log.md).
constexpr float kDefaultVoxelsPerCell = 16.f;
OccupancyGrid buildOccupancyGrid(const MeshView &mesh, float voxelsPerCell = kDefaultVoxelsPerCell);

} // namespace uvr
