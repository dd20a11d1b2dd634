// Procedural meshes of a box, one cell type at a time: shared by tests and benchmarks.
#pragma once

#include "mesh/mesh.h"

#include <functional>

namespace uvr {

/// An n x n x n lattice over `box`, each lattice cube cut into cells of `type` (6 Kuhn tetrahedra, 1
/// hexahedron, 2 wedges, or 6 pyramids around an added centre point), all wound as VTK expects. Interior
/// lattice points are moved by up to `jitter` of a cube's edge (seeded) so that cells are not affine images
/// of each other. One point field "f" holds `field` at every point, one cell field "f_cell" holds it at each
/// cell centroid.
UnstructuredGrid makeBoxGrid(CellType type, int n, const Box3f &box, const std::function<float(Vec3f)> &field,
                             float jitter = 0.f, unsigned seed = 1);

/// makeBoxGrid's lattice of pyramids whose pyramids on the box's sides are each cut into two tets: tets,
/// pyramids and the triangles they share.
UnstructuredGrid makePyramidsAndTets(int n, const Box3f &box, const std::function<float(Vec3f)> &field,
                                     float jitter = 0.f, unsigned seed = 1);

/// The cells of `grid` whose centre (the mean of their corners) `keep` takes, with the point field alone: the
/// cell field's values would no longer match the cells.
UnstructuredGrid keepCells(const UnstructuredGrid &grid, const std::function<bool(Vec3f)> &keep);

} // namespace uvr
