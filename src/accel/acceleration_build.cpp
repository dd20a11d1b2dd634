#include "accel/acceleration.h"

#include "mesh/cell_neighbors.h"
#include "mesh/tet_neighbors.h"

#include <unistd.h>

namespace uvr {

namespace {

/// Whether a structure that only speeds walks up may take `bytes`: the per-tet records (64 bytes a tet) and
/// the other cells' adjacency (cellAdjacencyBytes) would cost more than a large mesh on a small machine could
/// spare, so each is kept to an eighth of the memory.
bool walkAidFits(uint64_t bytes) {
  const long pages = sysconf(_SC_PHYS_PAGES), pageBytes = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && pageBytes > 0 && bytes <= uint64_t(pages) * uint64_t(pageBytes) / 8;
}

} // namespace

HostAcceleration buildHostAcceleration(const Mesh &mesh, const MeshView &view, uint32_t leafSize, bool lean) {
  HostAcceleration built;
  built.bvh = buildBvh(view);
  built.occupancy = buildOccupancyGrid(view);
  built.partitions = buildPartitions(view, leafSize);
  if (lean)
    return built;
  built.tetNeighbors = buildTetNeighbors(mesh);
  if (walkAidFits(cellAdjacencyBytes(view))) {
    built.cellNeighbors = buildCellNeighbors(mesh);
    built.cellFacePlanes = buildCellFacePlanes(view);
    linkTetsToOtherCells(view, built.cellNeighbors, built.tetNeighbors);
  }
  built.seeds = buildSeedGrid(view, built.tetNeighbors.empty() ? nullptr : built.tetNeighbors.data());
  if (!built.tetNeighbors.empty() && listsBoundaryFaces(view))
    built.boundaryFaceList = listBoundaryFaces(built.tetNeighbors);
  else if (!built.cellNeighbors.empty())
    built.boundaryFaceList = listBoundaryCellFaces(view, dataOrNull(built.tetNeighbors), built.cellNeighbors);
  if (!built.tetNeighbors.empty() && walkAidFits(view.tetCount * sizeof(TetAffine)))
    built.tetAffine = buildTetAffine(view);
  return built;
}

} // namespace uvr
