// Face adjacency of the pyramids, wedges and hexahedra, for walking from one sample's cell to the next as
// tets do (tet_neighbors.h): without it, a sample outside the previous sample's cell takes a BVH query whose
// candidates each cost a Newton solve.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// Faces per cell in the adjacency: the most any of these types has (a hexahedron's).
constexpr int kMaxCellFaces = 6;

/// A cell type's faces as corner numbers (VTK's numbering); a triangle's fourth corner is -1.
struct CellFaces {
  int count;
  int8_t corners[kMaxCellFaces][4];
};

UVR_HOST_DEVICE inline CellFaces cellFaces(CellType type) {
  switch (type) {
  case CellType::Pyramid:
    return {5, {{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}, {}}};
  case CellType::Wedge:
    return {5, {{0, 1, 2, -1}, {3, 5, 4, -1}, {0, 3, 4, 1}, {1, 4, 5, 2}, {2, 5, 3, 0}, {}}};
  case CellType::Hexahedron:
    return {6, {{0, 4, 7, 3}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 3, 2, 1}, {4, 5, 6, 7}}};
  default:
    return {0, {}};
  }
}

/// For each cell that is not a tet and each of its faces (cellFaces' order), the cell across it, a tet
/// included, or kNoCell: kMaxCellFaces entries per cell, at kMaxCellFaces * (cell - tet count). Empty for a
/// mesh of tets alone.
std::vector<uint32_t> buildCellNeighbors(const Mesh &mesh);

/// The most memory buildCellNeighbors and buildCellFacePlanes take together for `otherCells` cells that are
/// not tets: what they keep (120 bytes a cell) and the face keys the adjacency is sorted from.
uint64_t cellAdjacencyBytes(uint64_t otherCells);

/// Per cell that is not a tet, its faces' planes (cellFaces' order) as (n, w): n·p + w is how far `p` lies
/// beyond the face, in units of the cell's size (its centre's distance to its first corner). A quad's plane
/// is taken through its centre, normal to its diagonals' cross product; each normal is turned away from the
/// cell's centre, so any winding works. kMaxCellFaces entries per cell, a missing face never furthest.
std::vector<Vec4f> buildCellFacePlanes(const MeshView &mesh);

/// The face of the `index`-th cell that is not a tet whose plane `p` lies furthest beyond, and how far.
UVR_HOST_DEVICE inline int furthestFace(const Vec4f *planes, uint64_t index, Vec3f p, float &beyond) {
  const Vec4f *plane = planes + kMaxCellFaces * index;
  int furthest = 0;
  beyond = plane[0].x * p.x + plane[0].y * p.y + plane[0].z * p.z + plane[0].w;
  for (int f = 1; f < kMaxCellFaces; ++f) {
    const float distance = plane[f].x * p.x + plane[f].y * p.y + plane[f].z * p.z + plane[f].w;
    if (distance > beyond) {
      beyond = distance;
      furthest = f;
    }
  }
  return furthest;
}

} // namespace uvr
