// The acceleration data built on the GPU from the mesh already there: tet adjacency, the point-location
// BVH, the occupancy and seed grids and the partitions. The per-cell steps are the host build's own
// functions; what differs is how the work is spread (sorts and scans instead of recursion). The tet
// adjacency, the occupancy and seed grids and the partitions come out as the host builds them (the KD-tree's
// nodes laid out level by level rather than depth first); the BVH is a radix tree over the cells in Morton
// order, the host's is Embree's.
#pragma once

#include "accel/bvh.h"
#include "accel/occupancy.h"
#include "accel/partitions.h"
#include "accel/seed_grid.h"
#include "backend/cuda/device_buffer.cuh"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

struct DeviceAcceleration {
  DeviceBuffer<uint32_t> tetNeighbors;
  DeviceBuffer<BvhNode> bvhNodes;
  DeviceBuffer<uint32_t> bvhCellIds;
  DeviceBuffer<uint32_t> boundaryFaceList; ///< every boundary face, 4 * tet + i; empty where not listed
  DeviceBuffer<uint64_t> occupancyBits;
  OccupancyView occupancy; ///< device pointer to occupancyBits
  DeviceBuffer<uint32_t> seedCells;
  DeviceBuffer<uint32_t> boundaryStart, boundaryFaces; ///< empty where not listed
  DeviceBuffer<uint8_t> boundaryOctants;
  SeedGridView seeds; ///< device pointers to the four
  DeviceBuffer<KdNode> kdNodes;
  DeviceBuffer<Box3f> nodeBounds;
  DeviceBuffer<float> valueMin, valueMax;
  DeviceBuffer<unsigned long long> cellCounts; ///< cells listed per partition
  Box3f rootBounds;
  uint32_t partitionCount = 0;
  /// Milliseconds per step, in order, for reports.
  std::vector<std::pair<std::string, double>> stepMs;

  size_t bytes() const {
    return tetNeighbors.bytes() + bvhNodes.bytes() + bvhCellIds.bytes() + boundaryFaceList.bytes() +
           occupancyBits.bytes() + seedCells.bytes() + boundaryStart.bytes() + boundaryFaces.bytes() +
           boundaryOctants.bytes() + kdNodes.bytes() + nodeBounds.bytes() + valueMin.bytes() +
           valueMax.bytes() + cellCounts.bytes();
  }
};

/// Builds everything a ray reads besides the mesh and the transfer function, from `mesh` (device pointers;
/// `pointCount` points), with partitions of at most `leafSize` cells where they can be split.
void buildOnDevice(const MeshView &mesh, uint64_t pointCount, uint32_t leafSize, DeviceAcceleration &out);

} // namespace uvr
