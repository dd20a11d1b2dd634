// A plain, pointer-and-count view of a mesh and one of its fields: what the integrator reads on host and
// device.
#pragma once

#include "core/vec.h"
#include "mesh/mesh.h"

#include <cmath>
#include <cstdint>

namespace uvr {

struct MeshView {
  const Vec3f *points = nullptr;
  const uint32_t *tets = nullptr;
  const uint32_t *pyramids = nullptr;
  const uint32_t *wedges = nullptr;
  const uint32_t *hexes = nullptr;
  uint64_t tetCount = 0;
  uint64_t pyramidCount = 0;
  uint64_t wedgeCount = 0;
  uint64_t hexCount = 0;
  const float *values = nullptr; ///< the rendered field, per point or per cell
  bool cellCentered = false;
  /// The mean cellSizeLog2 that partitions' step scales compare theirs with: NaN for this mesh's own, the
  /// whole mesh's for a piece of one (MeshPiece).
  double stepScaleReference = NAN;
  /// For a piece of a mesh: its region and the whole mesh's bounds (empty for a whole mesh). Its partitions
  /// are then the whole mesh's within the region: the tree is built over the cells whose centroids lie in
  /// it, from the region's box down, padded as the whole mesh's.
  Box3f pieceRegion, pieceWholeBounds;

  UVR_HOST_DEVICE uint64_t cellCount() const { return tetCount + pyramidCount + wedgeCount + hexCount; }
};

/// A view of `mesh` whose values come from field `fieldIndex`; -1 for geometry alone.
inline MeshView makeMeshView(const Mesh &mesh, int fieldIndex) {
  MeshView view;
  view.points = mesh.points.data();
  view.tets = mesh.tets.data();
  view.pyramids = mesh.pyramids.data();
  view.wedges = mesh.wedges.data();
  view.hexes = mesh.hexes.data();
  view.tetCount = mesh.tetCount();
  view.pyramidCount = mesh.pyramidCount();
  view.wedgeCount = mesh.wedgeCount();
  view.hexCount = mesh.hexCount();
  if (fieldIndex >= 0) {
    view.values = mesh.fields[size_t(fieldIndex)].values.data();
    view.cellCentered = mesh.fields[size_t(fieldIndex)].centering == Centering::Cell;
  }
  return view;
}

} // namespace uvr
