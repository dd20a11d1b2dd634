// The host mesh: points, cells grouped by type, and scalar fields.
#pragma once

#include "core/buffer.h"
#include "core/vec.h"

#include <uvr/mesh.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace uvr {

/// One scalar value per point or per cell. Arrays with several components become their magnitude.
struct ScalarField {
  std::string name;
  Centering centering = Centering::Point;
  UninitVector<float> values;
  uint64_t components = 1; ///< of the file's array before the magnitude (kept by the readers of polyhedra)
};

/// Polyhedra of a file (VTK type 42) and the tetrahedra and pyramids they were decomposed into on load.
struct PolyhedronCounts {
  uint64_t polyhedra = 0, tets = 0, pyramids = 0;
};

/// Cells exactly as VTK files store them (offsets + connectivity + type codes): what every reader produces.
struct UnstructuredGrid {
  UninitVector<Vec3f> points;
  std::vector<int64_t> offsets; ///< cell count + 1 entries, offsets[0] == 0
  std::vector<int64_t> connectivity;
  std::vector<uint8_t> types; ///< VTK cell type codes, any dimension
  std::vector<ScalarField> fields;
  PolyhedronCounts polyhedra; ///< already decomposed (see mesh/polyhedra.h): no cell here is of type 42
};

/// Number of vertices of a volume cell type; 0 for any other VTK type code.
int vertexCount(uint8_t vtkType);

/// Cells grouped by type in the order tets, pyramids, wedges, hexahedra (umesh's layout: no offsets, no type
/// array). A cell's index is its position in that order; cell fields follow it. Every cell is wound as VTK
/// expects (positive volume): inverted cells are reordered on construction. The arrays start uninitialized
/// when sized, for the readers' parallel loops to fill.
struct Mesh {
  UninitVector<Vec3f> points;
  UninitVector<uint32_t> tets;     ///< 4 point indices per cell
  UninitVector<uint32_t> pyramids; ///< 5
  UninitVector<uint32_t> wedges;   ///< 6
  UninitVector<uint32_t> hexes;    ///< 8
  std::vector<ScalarField> fields;

  uint64_t skippedCells = 0;  ///< lower-dimensional cells of the file that were not kept
  uint64_t invertedCells = 0; ///< cells whose winding was reversed on construction
  PolyhedronCounts polyhedra; ///< the file's polyhedra, whose pieces are among the tets and pyramids

  uint64_t tetCount() const { return tets.size() / 4; }
  uint64_t pyramidCount() const { return pyramids.size() / 5; }
  uint64_t wedgeCount() const { return wedges.size() / 6; }
  uint64_t hexCount() const { return hexes.size() / 8; }
  uint64_t cellCount() const { return tetCount() + pyramidCount() + wedgeCount() + hexCount(); }

  Box3f bounds() const;
  /// Index into `fields`, or -1. `name` may say the centring, "point:p" or "cell:p"; a plain name where a
  /// point and a cell field share it finds the point field.
  int findField(const std::string &name) const;
};

/// Reorders the corners `v` of a cell of `type` so that it is wound as VTK expects (positive volume; VTK's
/// wedge base faces away from its top). Returns whether it was inverted.
bool orientCell(CellType type, uint32_t *v, std::span<const Vec3f> points);

/// Groups the volume cells of `grid` by type, fixes their winding, orders them spatially and reorders the
/// fields to match. Lower-dimensional cells are dropped and counted; `source` names the file in errors.
Mesh buildMesh(UnstructuredGrid &&grid, const std::string &source);

/// The points' check that every reader and VolumeMesh::fromArrays share (buildMesh calls it): throws
/// uvr::Error naming the first point with a coordinate that is not finite.
void checkPoints(std::span<const Vec3f> points, const std::string &source);

/// The cell arrays of an unstructured grid as VTK stores them, viewed in place (e.g. numpy arrays handed over
/// from Python), so that building a mesh from them copies nothing twice. Point indices are VTK's 64 bits, or
/// 32 where a reader narrowed them as it checked them (half the memory to write and read again).
template <typename Index> struct CellArrays {
  std::span<const int64_t> offsets; ///< cell count + 1 entries, offsets[0] == 0
  std::span<const Index> connectivity;
  std::span<const uint8_t> types;
};
using CellArraysView = CellArrays<int64_t>;

/// buildMesh over cells viewed in place; the offsets are checked against the connectivity.
Mesh buildMesh(UninitVector<Vec3f> &&points, CellArraysView cells, std::vector<ScalarField> &&fields,
               const std::string &source);

/// Cell arrays that a reader hands over to buildMesh, point indices narrowed to 32 bits as they were read
/// (half the memory to write and read again).
struct CellBuffers {
  Buffer<int64_t> offsets; ///< cell count + 1 entries, offsets[0] == 0
  Buffer<uint32_t> connectivity;
  Buffer<uint8_t> types;

  CellArrays<uint32_t> view() const { return {offsets, connectivity, types}; }
};

/// buildMesh over cell arrays handed over. When all cells are of one linear volume type, back to back in the
/// connectivity (a tetrahedral mesh, say), the connectivity becomes that type's cell array as it is: there is
/// nothing to group or copy.
Mesh buildMesh(UninitVector<Vec3f> &&points, CellBuffers &&cells, std::vector<ScalarField> &&fields,
               const std::string &source);

/// Sorts each cell type's cells along a Morton curve through their centroids and numbers the points by first
/// use, so that neighbouring cells and their corners lie close in memory: point location walks and BVH
/// queries then hit the cache. Files often list cells in no spatial order at all. Fields follow.
void orderSpatially(Mesh &mesh);

/// The cells of `mesh` where `keep` (one entry per cell, in cell order) is nonzero, with the fields
/// `fields` of `mesh` and the points those cells use: each type's cells in their order in `mesh` (so still
/// ordered spatially) and wound as there, the points numbered by first use. Nothing is checked again.
Mesh selectCells(const Mesh &mesh, std::span<const uint8_t> keep, std::span<const int> fields);

} // namespace uvr
