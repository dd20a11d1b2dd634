// Data-parallel rendering without the messaging: the mesh's split into convex regions by the top levels of a
// KD-tree, each region's piece of the mesh, and the order the regions' images composite in.
#pragma once

#include <uvr/mesh.h>
#include <uvr/vec.h>

#include <vector>

namespace uvr {

/// Regions of space split by planes, one per rank: a KD-tree whose leaves are the regions.
struct RegionTree {
  struct Node {
    int axis = -1; ///< -1 for a region
    float split = 0.f;
    int below = -1, above = -1; ///< children: the sides axis < split and axis > split
    int region = -1;            ///< for a region, its index (the rank that draws it)
  };
  std::vector<Node> nodes; ///< the root first
  std::vector<Box3f> regions;
};

/// Splits space around `mesh` into `count` regions of about as many cells each (by their centroids), each
/// split at a median across the longest side of its cells' centroids. The outer regions reach well past the
/// mesh's bounds, so that only the split planes clip rays.
RegionTree splitIntoRegions(const VolumeMesh &mesh, int count);

/// The cells of `mesh` that touch `region` (their boxes meet it; a cell across a split belongs to every
/// region it touches), with field `fieldIndex` alone.
VolumeMesh meshPiece(const VolumeMesh &mesh, int fieldIndex, const Box3f &region);

/// The regions front to back as seen from `eye`: a side of each split plane wholly before the other.
std::vector<int> visibilityOrder(const RegionTree &tree, Vec3f eye);

} // namespace uvr
