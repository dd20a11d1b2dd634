// Where a regular grid of voxels lies over the mesh bounds: the placement the occupancy grid and the seed
// grid share, and the mapping of points to voxels both look up. Plain data, usable on host and device.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"

#include <cstdint>

namespace uvr {

struct VoxelGrid {
  Vec3f origin;
  Vec3f voxelsPerUnit;
  Vec3f voxelSize; ///< the extent over the voxel count, per axis
  int nx = 0, ny = 0, nz = 0;

  UVR_HOST_DEVICE uint64_t voxelCount() const { return uint64_t(nx) * uint64_t(ny) * uint64_t(nz); }
  UVR_HOST_DEVICE float voxelEdge() const { return maxf(voxelSize.x, maxf(voxelSize.y, voxelSize.z)); }

  /// The voxel holding `p`; false outside the grid (and for NaN).
  UVR_HOST_DEVICE bool voxelOf(Vec3f p, int &x, int &y, int &z) const {
    const float fx = (p.x - origin.x) * voxelsPerUnit.x, fy = (p.y - origin.y) * voxelsPerUnit.y,
                fz = (p.z - origin.z) * voxelsPerUnit.z;
    if (!(fx >= 0.f && fy >= 0.f && fz >= 0.f)) // also rejects NaN
      return false;
    x = int(fx), y = int(fy), z = int(fz);
    return x < nx && y < ny && z < nz;
  }
  /// Voxels are numbered x fastest.
  UVR_HOST_DEVICE uint64_t index(int x, int y, int z) const {
    return (uint64_t(z) * uint64_t(ny) + uint64_t(y)) * uint64_t(nx) + uint64_t(x);
  }
  UVR_HOST_DEVICE Vec3f centre(int x, int y, int z) const {
    return {origin.x + (float(x) + 0.5f) * voxelSize.x, origin.y + (float(y) + 0.5f) * voxelSize.y,
            origin.z + (float(z) + 0.5f) * voxelSize.z};
  }
};

/// About `voxelsPerCell` cubic voxels per cell of a mesh of `cells` cells within `bounds`, the count capped
/// so that a grid stays a small fraction of the mesh's memory.
VoxelGrid placeVoxelGrid(const Box3f &bounds, uint64_t cells, float voxelsPerCell);

struct MeshView;
/// The same over the box of `mesh`'s cells, reduced on the host's cores.
VoxelGrid placeVoxelGrid(const MeshView &mesh, float voxelsPerCell);

} // namespace uvr
