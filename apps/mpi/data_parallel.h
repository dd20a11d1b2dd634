// Data-parallel rendering without the messaging: the piece of the mesh that a rank keeps for its region
// (uvr::splitIntoRegions).
#pragma once

#include <uvr/mesh.h>
#include <uvr/vec.h>

namespace uvr {

/// The cells of `mesh` that touch `region` (their boxes meet it; a cell across a split belongs to every
/// region it touches), with field `fieldIndex` alone.
VolumeMesh meshPiece(const VolumeMesh &mesh, int fieldIndex, const Box3f &region);

/// The cells of `mesh` that `region` owns, with every field: those whose box centre lies in it, taken
/// half-open (lower <= centre < upper) as the partitions' tree assigns cells. The regions of one split own
/// each cell once.
VolumeMesh ownedCells(const VolumeMesh &mesh, const Box3f &region);

} // namespace uvr
