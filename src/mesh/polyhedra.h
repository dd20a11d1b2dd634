// Polyhedral cells (VTK type 42), decomposed on load into tetrahedra and pyramids around their centres.
#pragma once

#include "mesh/mesh.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace uvr {

constexpr uint8_t kVtkPolyhedron = 42;

/// The faces of a grid's polyhedra, in the order of its type-42 cells: polyhedron k has the faces
/// faceIds[cellOffsets[k] .. cellOffsets[k + 1]), face f the points facePoints[faceOffsets[f] ..
/// faceOffsets[f + 1]). Faces listed in line with their cells (legacy files, .vtu's `faces`) have faceIds 0,
/// 1, 2, ...; VTK 9.4's .vtu shares them between cells.
struct PolyhedronFaces {
  std::vector<int64_t> cellOffsets{0};
  std::vector<int64_t> faceIds;
  std::vector<int64_t> faceOffsets{0};
  std::vector<int64_t> facePoints;

  size_t polyhedronCount() const { return cellOffsets.size() - 1; }

  /// Appends a polyhedron given as VTK's face stream [nFaces, nPoints0, ids..., nPoints1, ids..., ...],
  /// which must fill `stream` exactly. Throws uvr::Error naming `source` and `where` otherwise.
  void appendStream(std::span<const int64_t> stream, const std::string &source, const std::string &where);
};

/// Replaces each cell of type 42 in `grid` (its connectivity entries are not used) by tetrahedra and
/// pyramids: a new point at the average of its points, and for each face a tetrahedron (triangle) or a
/// pyramid (quad) with that point as apex; faces of more points are fanned into triangles from their
/// lowest-numbered point, which both cells of a face agree on. Each piece is wound as VTK expects, whichever
/// way the face turns; cell fields are copied to the pieces. Counts them in grid.polyhedra. A point field's
/// value at the new point is the cell's value of the cell field of the same name and component count where
/// there is one (and that value is not NaN), else the average of the field's values at the cell's points.
/// Throws uvr::Error naming `source` for polyhedra without faces, faces of fewer than 3 points, point indices
/// outside the points, face ids outside the faces, and faces used by more than two polyhedra (so that a small
/// file cannot ask for a huge mesh).
void decomposePolyhedra(UnstructuredGrid &grid, const PolyhedronFaces &faces, const std::string &source);

} // namespace uvr
