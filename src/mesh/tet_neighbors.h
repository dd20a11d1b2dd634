// Face adjacency of the tetrahedra, for walking from one sample's cell to the next.
#pragma once

#include "mesh/mesh.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// For each tet and each of its vertices i, the tet across the face opposite vertex i, or 0xffffffff on the
/// boundary: 4 entries per tet, indexed as the cells are.
std::vector<uint32_t> buildTetNeighbors(const Mesh &mesh);

} // namespace uvr
