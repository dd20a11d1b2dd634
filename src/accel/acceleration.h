// Everything a ray reads besides the mesh and the transfer function, in host memory (built here for the CPU
// backend, or what the GPU built, copied back for checks) or in a backend's device memory.
#pragma once

#include "accel/bvh.h"
#include "accel/occupancy.h"
#include "accel/partitions.h"
#include "accel/seed_grid.h"
#include "core/storage.h"
#include "mesh/mesh.h"
#include "mesh/mesh_view.h"
#include "mesh/tet_affine.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// Each array a backend builds, and the values placed beside them, listed once (forEachMember): the views
/// (see makeSceneView), the byte counts and the copies between host and device all come from this list.
/// The walk aids (the other cells' adjacency and planes, the tet records) are built by the host alone.
template <typename Storage> struct Acceleration {
  template <typename T> using Array = typename Storage::template Array<T>;
  BvhArrays<Storage> bvh;
  OccupancyBits<Storage> occupancy;
  SeedGridArrays<Storage> seeds;
  Array<uint32_t> tetNeighbors;     ///< 4 per tet; see buildTetNeighbors, linkTetsToOtherCells
  Array<uint32_t> cellNeighbors;    ///< empty for tets alone, or where memory is short
  Array<Vec4f> cellFacePlanes;      ///< likewise
  Array<uint32_t> boundaryFaceList; ///< for the per-frame crossings; empty where the grid lists none
  PartitionArrays<Storage> partitions;
  Array<TetAffine> tetAffine; ///< host walks only; empty where they would take too much memory

  template <typename A, typename B, typename F> static void forEachMember(A &a, B &b, F &&f) {
    BvhArrays<Storage>::forEachMember(a.bvh, b.bvh, f);
    OccupancyBits<Storage>::forEachMember(a.occupancy, b.occupancy, f);
    SeedGridArrays<Storage>::forEachMember(a.seeds, b.seeds, f);
    f(a.tetNeighbors, b.tetNeighbors);
    f(a.cellNeighbors, b.cellNeighbors);
    f(a.cellFacePlanes, b.cellFacePlanes);
    f(a.boundaryFaceList, b.boundaryFaceList);
    PartitionArrays<Storage>::forEachMember(a.partitions, b.partitions, f);
    f(a.tetAffine, b.tetAffine);
  }
  size_t bytes() const { return storageBytes(*this); }
};
using HostAcceleration = Acceleration<HostStorage>;

/// Builds it all on the host with all cores, partitions of at most `leafSize` cells. The structures that only
/// speed walks up (the other cells' adjacency, the tet records) are left out where they would take more than
/// an eighth of the machine's memory; `lean` (MemoryLayout::Lean) leaves out every walk's structure: the tet
/// and cell adjacency, the seed grid, the boundary faces and the tet records.
HostAcceleration buildHostAcceleration(const Mesh &mesh, const MeshView &view, uint32_t leafSize,
                                       bool lean = false);

} // namespace uvr
