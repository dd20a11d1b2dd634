// Data-parallel rendering without the messaging: the piece of the mesh that a rank keeps for its region
// (uvr::splitIntoRegions).
#pragma once

#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/vec.h>

#include <string>
#include <vector>

namespace uvr {

/// The regions of a split of space into `count` regions, `pieceRegions.size() / count` consecutive pieces
/// each, where `pieceRegions` are the regions of splitIntoRegions(mesh, pieces) in order: for `count` the
/// piece count, or a power of 2 dividing it, splitIntoRegions(mesh, count) itself (its median splits are the
/// pieces'). Throws uvr::Error where the boxes are no such split.
MeshRegions regionsOfPieces(const std::vector<Box3f> &pieceRegions, int count);

/// The cells of `mesh` that touch `region` (their boxes meet it; a cell across a split belongs to every
/// region it touches), with field `fieldIndex` alone.
VolumeMesh meshPiece(const VolumeMesh &mesh, int fieldIndex, const Box3f &region);

/// The cells of `mesh` that `region` owns, with every field: those whose box centre lies in it, taken
/// half-open (lower <= centre < upper) as the partitions' tree assigns cells. The regions of one split own
/// each cell once.
VolumeMesh ownedCells(const VolumeMesh &mesh, const Box3f &region);

/// The cells of `mesh` whose boxes touch `region` but that it does not own (see ownedCells), with every
/// field: what a piece's region needs of the other pieces' cells.
VolumeMesh ghostCells(const VolumeMesh &mesh, const Box3f &region);

/// Of the ghost cells of one of several pieces that one process reads together, those it has no other way:
/// owned by none of the pieces' regions `owned`, and touching none of the regions `earlier` (whose ghost
/// cells hold them already).
VolumeMesh ghostCellsOutside(const VolumeMesh &ghosts, const std::vector<Box3f> &owned,
                             const std::vector<Box3f> &earlier);

/// The cells of `parts` (with the same fields, in the same order) as one mesh, the points of later parts at
/// an earlier part's point's coordinates joined with it.
VolumeMesh mergeMeshes(const std::vector<VolumeMesh> &parts, const std::string &source);

} // namespace uvr
