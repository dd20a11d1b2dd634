// A bit per voxel of a grid over the mesh bounds, set where some cell's box reaches: most samples that fall
// in no cell (empty space inside the bounds, concavities of the mesh) are rejected by one load instead of a
// failed walk and a failed BVH query. Flat arrays, usable on host and device.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

struct OccupancyView {
  const uint64_t *bits = nullptr; ///< null: every point may lie in a cell
  Vec3f origin;
  Vec3f voxelsPerUnit;
  int nx = 0, ny = 0, nz = 0;

  /// False only where no cell can hold `p`.
  UVR_HOST_DEVICE bool mayHoldCell(Vec3f p) const {
    if (!bits)
      return true;
    const float fx = (p.x - origin.x) * voxelsPerUnit.x, fy = (p.y - origin.y) * voxelsPerUnit.y,
                fz = (p.z - origin.z) * voxelsPerUnit.z;
    if (!(fx >= 0.f && fy >= 0.f && fz >= 0.f)) // also rejects NaN
      return false;
    const int x = int(fx), y = int(fy), z = int(fz);
    if (x >= nx || y >= ny || z >= nz)
      return false;
    const uint64_t voxel = (uint64_t(z) * uint64_t(ny) + uint64_t(y)) * uint64_t(nx) + uint64_t(x);
    return (bits[voxel >> 6] >> (voxel & 63)) & 1u;
  }
};

struct OccupancyGrid {
  std::vector<uint64_t> bits;
  Vec3f origin, voxelsPerUnit;
  Vec3f voxelSize; ///< the extent over the voxel count, per axis
  int nx = 0, ny = 0, nz = 0;

  OccupancyView view() const { return {bits.data(), origin, voxelsPerUnit, nx, ny, nz}; }
  uint64_t wordCount() const { return (uint64_t(nx) * uint64_t(ny) * uint64_t(nz) + 63) / 64; }
  size_t memoryBytes() const { return bits.size() * sizeof(uint64_t); }
};

/// About `voxelsPerCell` voxels per cell over the mesh bounds (a bit each), set where a cell may reach (its
/// box; for a tet, the part of its box its face planes do not exclude). The default, 16, made `full` frames
/// 7-12% faster than 4 on the brain meshes (fewer samples near the surface left to a BVH query that finds
/// nothing), for 2 bytes per cell and a longer build.
constexpr float kDefaultVoxelsPerCell = 16.f;
OccupancyGrid buildOccupancyGrid(const MeshView &mesh, float voxelsPerCell = kDefaultVoxelsPerCell);

} // namespace uvr
