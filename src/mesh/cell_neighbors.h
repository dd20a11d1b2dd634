// Face adjacency of the pyramids, wedges and hexahedra, for walking from one sample's cell to the next as
// tets do (tet_neighbors.h): without it, a sample outside the previous sample's cell takes a BVH query whose
// candidates each cost a Newton solve.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <span>
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

/// Boundary faces (cell faces with no cell across) are numbered (cell << bits) + face: 2 bits in a mesh of
/// tets alone (4 * tet + i, face i being the one opposite corner i), so that up to 2^30 tets number theirs
/// in 32 bits; 3 bits where there are other cells (their faces in cellFaces' order, a tet's as above).
UVR_HOST_DEVICE inline uint32_t boundaryFaceBits(const MeshView &mesh) {
  return mesh.cellCount() == mesh.tetCount ? 2u : 3u;
}

/// The cell that boundary face `face` bounds.
UVR_HOST_DEVICE inline uint32_t boundaryFaceCell(const MeshView &mesh, uint32_t face) {
  return face >> boundaryFaceBits(mesh);
}

/// The corners of boundary face `face` in order around it, into `corners`: 3, or 4 for a quadrilateral; and
/// into `inner` a point on the cell's side of the face (a tet's opposite corner, another cell's centre).
UVR_HOST_DEVICE inline int boundaryFaceCorners(const MeshView &mesh, uint32_t face, Vec3f corners[4],
                                               Vec3f &inner) {
  const uint32_t bits = boundaryFaceBits(mesh), i = face & ((1u << bits) - 1u);
  int count;
  const uint32_t *v = cellCorners(mesh, face >> bits, count);
  if (count == 4) {
    for (uint32_t k = 0; k < 3; ++k)
      corners[k] = mesh.points[v[(i + 1 + k) & 3u]];
    inner = mesh.points[v[i]];
    return 3;
  }
  Vec3f centre{};
  for (int k = 0; k < count; ++k)
    centre = centre + mesh.points[v[k]];
  inner = centre * (1.f / float(count));
  const CellFaces faces = cellFaces(cellType(mesh, face >> bits));
  const int8_t *c = faces.corners[i];
  const int cornerCount = c[3] < 0 ? 3 : 4;
  for (int k = 0; k < cornerCount; ++k)
    corners[k] = mesh.points[v[c[k]]];
  return cornerCount;
}

/// The boundary faces of a mesh that has other cells than tets, numbered as boundaryFaceBits says, in
/// increasing order: the faces with no cell across in `cellNeighbors` (buildCellNeighbors) or, for a tet,
/// in `tetNeighbors` (buildTetNeighbors, null where there are no tets) with no other cell sharing it. Empty
/// for a mesh of tets alone or of more than 2^29 cells.
std::vector<uint32_t> listBoundaryCellFaces(const MeshView &mesh, const uint32_t *tetNeighbors,
                                            const std::vector<uint32_t> &cellNeighbors);

/// Gives each tet face that another cell shares, which `tetNeighbors` (buildTetNeighbors: 4 per tet, tets
/// alone) leaves at kNoCell, that cell, as `cellNeighbors` (buildCellNeighbors) names it: a walk through tets
/// then goes on into the other cells rather than stop as at the boundary.
void linkTetsToOtherCells(const MeshView &mesh, const std::vector<uint32_t> &cellNeighbors,
                          std::span<uint32_t> tetNeighbors);

/// For each cell that is not a tet and each of its faces (cellFaces' order), the cell across it, a tet
/// included, or kNoCell: kMaxCellFaces entries per cell, at kMaxCellFaces * (cell - tet count). Empty for a
/// mesh of tets alone.
std::vector<uint32_t> buildCellNeighbors(const Mesh &mesh);

/// The most memory buildCellNeighbors and buildCellFacePlanes take together for `mesh`: what they keep (24
/// bytes a cell that is not a tet, 96 more a pyramid or wedge) and the face keys the adjacency is sorted
/// from.
uint64_t cellAdjacencyBytes(const MeshView &mesh);

/// Per pyramid and wedge, its faces' planes (cellFaces' order) as (n, w): n·p + w is how far `p` lies beyond
/// the face, in units of the cell's size (its centre's distance to its first corner). A quad's plane is
/// taken through its centre, normal to its diagonals' cross product; each normal is turned away from the
/// cell's centre, so any winding works. kMaxCellFaces entries per cell, at kMaxCellFaces * (cell - tet
/// count), a missing face never furthest. Hexahedra have none: a walk crosses them by their parametric
/// coordinates (walkCells).
std::vector<Vec4f> buildCellFacePlanes(const MeshView &mesh);

/// The face of the `index`-th cell that is not a tet whose plane `p` lies furthest beyond, and how far; and
/// in `beyondTriangles` how far beyond the furthest of the faces in `triangles` (a bit per face). A triangle
/// lies in its plane, a quad of a distorted cell need not.
UVR_HOST_DEVICE inline int furthestFace(const Vec4f *planes, uint64_t index, Vec3f p, unsigned triangles,
                                        float &beyond, float &beyondTriangles) {
  const Vec4f *plane = planes + kMaxCellFaces * index;
  int furthest = 0;
  beyond = beyondTriangles = -INFINITY;
  for (int f = 0; f < kMaxCellFaces; ++f) {
    const float distance = plane[f].x * p.x + plane[f].y * p.y + plane[f].z * p.z + plane[f].w;
    if (distance > beyond) {
      beyond = distance;
      furthest = f;
    }
    if (triangles >> f & 1u)
      beyondTriangles = maxf(beyondTriangles, distance);
  }
  return furthest;
}

/// The faces of a pyramid and of a wedge that are triangles, a bit per face in cellFaces' order.
constexpr unsigned kPyramidTriangles = 0b11110u, kWedgeTriangles = 0b00011u;

} // namespace uvr
