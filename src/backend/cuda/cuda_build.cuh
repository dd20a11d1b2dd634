// The acceleration data built on the GPU from the mesh already there: tet adjacency, the point-location
// BVH, the occupancy and seed grids and the partitions. The per-cell steps are the host build's own
// functions; what differs is how the work is spread (sorts and scans instead of recursion). The tet
// adjacency, the occupancy and seed grids and the partitions come out as the host builds them (the KD-tree's
// nodes laid out level by level rather than depth first); the BVH is a radix tree over the cells in Morton
// order, the host's is Embree's.
#pragma once

#include "accel/acceleration.h"
#include "backend/cuda/device_buffer.cuh"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

using DeviceAcceleration = Acceleration<DeviceStorage>;

/// Builds everything a ray reads besides the mesh and the transfer function, from `mesh` (device pointers;
/// `pointCount` points), with partitions of at most `leafSize` cells where they can be split; `lean`: without
/// the tet adjacency, the seed grid and the boundary faces (MemoryLayout::Lean). Returns the milliseconds per
/// step, in order, for reports.
std::vector<std::pair<std::string, double>> buildOnDevice(const MeshView &mesh, uint64_t pointCount,
                                                          uint32_t leafSize, bool lean,
                                                          DeviceAcceleration &out);

} // namespace uvr
