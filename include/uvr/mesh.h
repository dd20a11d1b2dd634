// Volume meshes: tetrahedra, hexahedra, wedges and pyramids with scalar fields per point or per cell, loaded
// from files or built from arrays laid out as VTK lays them out (vtkUnstructuredGrid, PyVista).
#pragma once

#include <uvr/io.h>
#include <uvr/settings.h>
#include <uvr/vec.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

/// Volume cell types, numbered as VTK numbers them.
enum class CellType : uint8_t { Tetra = 10, Hexahedron = 12, Wedge = 13, Pyramid = 14 };

enum class Centering : uint8_t { Point, Cell };

struct ValueRange {
  float min = 0.f, max = 0.f;
};

/// Cell volumes (absolute; hexahedra, wedges and pyramids through a split into tetrahedra).
struct VolumeStats {
  double min = 0.0, median = 0.0, max = 0.0;
  double p1 = 0.0, p99 = 0.0; ///< 1st and 99th percentiles: their ratio shows how graded a mesh is
  /// The median of each cell's volume per tetrahedron it splits into (hexahedron 6, wedge 3, pyramid 2): a
  /// cell's size measured alike for every type, which the default step is taken from.
  double medianPerTet = 0.0;
};

struct CellCounts {
  uint64_t tet = 0, hex = 0, wedge = 0, pyramid = 0;
  uint64_t skipped = 0;  ///< lower-dimensional cells of the input that were not kept
  uint64_t inverted = 0; ///< cells whose winding was reversed on load (they render as the others)
  /// Polyhedra of the file (VTK type 42), decomposed on load into tetrahedra and pyramids around their
  /// centres: these pieces are counted in `tet` and `pyramid` too.
  uint64_t polyhedron = 0, polyhedronTets = 0, polyhedronPyramids = 0;

  uint64_t total() const { return tet + hex + wedge + pyramid; }
};

struct FieldInfo {
  std::string name;
  Centering centering = Centering::Point;
};

/// Numbers viewed in place, float or double, `components` per tuple.
struct ArrayView {
  const void *data = nullptr;
  size_t tuples = 0;
  int components = 1;
  bool isDouble = false;

  ArrayView() = default;
  /// `values` holds `values.size() / components` tuples.
  ArrayView(std::span<const float> values, int components = 1)
      : data(values.data()), tuples(components > 0 ? values.size() / size_t(components) : 0),
        components(components) {}
  ArrayView(std::span<const double> values, int components = 1)
      : data(values.data()), tuples(components > 0 ? values.size() / size_t(components) : 0),
        components(components), isDouble(true) {}
};

/// A field given as an array: one tuple per point or per cell. Several components are kept as their
/// Euclidean magnitude.
struct FieldArray {
  std::string name;
  Centering centering = Centering::Point;
  ArrayView values;
};

/// A mesh as VTK 9 stores an unstructured grid, viewed in place (vtkUnstructuredGrid's arrays; PyVista's
/// points, offsets, cell_connectivity, celltypes, point_data and cell_data).
struct MeshArrays {
  ArrayView points;                      ///< 3 components per point
  std::span<const int64_t> offsets;      ///< cell count + 1 entries, offsets[0] == 0
  std::span<const int64_t> connectivity; ///< point indices, cell after cell
  std::span<const uint8_t> types;        ///< VTK cell type codes; cells of other dimensions are skipped
  std::vector<FieldArray> fields;
};

namespace detail {
struct Access;
}

/// A volume mesh, shared: copies are cheap and refer to the same data, which nothing changes after it is
/// made (withFields makes a new mesh). Cells are held grouped by type (tets, pyramids, wedges, hexahedra),
/// each wound as VTK expects, and ordered spatially; points are numbered by first use; fields follow.
/// Errors name the mesh's source: its file, or what fromArrays was given.
class VolumeMesh {
public:
  /// An empty mesh: no points, cells or fields.
  VolumeMesh();

  /// Reads a mesh file of any format uvr reads (see <uvr/io.h>). Throws uvr::Error naming the file and the
  /// position in it.
  static VolumeMesh load(const std::string &path, const LoadOptions &options = {});
  /// Builds a mesh from arrays, copying each once. Throws uvr::Error naming `source` for cells with bad
  /// offsets, types or point indices, and fields of the wrong length.
  static VolumeMesh fromArrays(const MeshArrays &arrays, const std::string &source = "uvr::VolumeMesh");

  /// Writes the mesh in the format the extension names (.vtu, .umesh; umesh holds point fields only).
  void save(const std::string &path, const SaveOptions &options = {}) const;

  /// The file it was read from, or the source fromArrays was given.
  const std::string &source() const;

  uint64_t pointCount() const;
  uint64_t cellCount() const;
  CellCounts cellCounts() const;
  Box3f bounds() const;

  /// The points, in the mesh's order.
  std::span<const Vec3f> points() const;
  /// The point indices of the cells of `type`, 4, 5, 6 or 8 per cell (tet, pyramid, wedge, hexahedron) in
  /// VTK's corner order. A cell's index is its position in the order tets, pyramids, wedges, hexahedra.
  std::span<const uint32_t> cells(CellType type) const;

  int fieldCount() const;
  FieldInfo field(int index) const;
  /// One value per point or per cell, in the mesh's order.
  std::span<const float> fieldValues(int index) const;
  /// The range of the field's finite values; {0, 0} when it has none.
  ValueRange fieldRange(int index) const;
  /// The index of the field named `name`, or -1. A prefix "point:" or "cell:" picks the field of that
  /// centring (a file may hold a point and a cell field of one name); a plain name picks the point field
  /// where there are both, else the first field of that name.
  int findField(const std::string &name) const;
  /// The index of the field to render: `name` (as findField takes it), or the first field when empty. Throws
  /// uvr::Error naming the source when the mesh has no volume cells or no fields, or no field `name` (listing
  /// the fields).
  int chooseField(const std::string &name) const;
  /// A mesh with only the fields `indices`, in that order. Moves the data when this is its only handle.
  VolumeMesh withFields(const std::vector<int> &indices) &&;
  /// The mesh of the cells where `keep` (one entry per cell, in the mesh's cell order) is nonzero, with the
  /// fields `indices` and the points those cells use: a piece of this mesh, its cells in their order here,
  /// made without the checks and the spatial sort that fromArrays would do again. Throws uvr::Error naming
  /// the source when `keep` has not one entry per cell or an index names no field.
  VolumeMesh selectCells(std::span<const uint8_t> keep, const std::vector<int> &indices) const;

  /// Computed once per mesh.
  VolumeStats volumeStats() const;
  /// The default step s1: the edge of a cube of the median cell volume, about half a typical tet's edge, so
  /// that a ray takes about two samples per cell it crosses.
  float defaultStep() const;
  /// What the partitions a renderer makes with `leafSize` (kAutoLeafSize: the default) scale steps that
  /// follow the mesh against: the mean size of their cells (log2 of the volume of a cell's box, in 1/256ths,
  /// over the partitions' cells), and the least of their step scales. Builds them.
  struct StepScaleReference {
    double meanCellSizeLog2 = 0.0;
    float finestStepScale = 1.f;
  };
  StepScaleReference stepScaleReference(uint32_t leafSize = kAutoLeafSize) const;
  /// A piece's part of its whole mesh's StepScaleReference, for the pieces of a mesh split among processes:
  /// per partition a renderer makes of this piece in `region` (one of splitIntoRegions' for the whole mesh,
  /// whose bounds are `wholeBounds`) with `leafSize`, the sum of its cells' sizes and their count. The
  /// pieces' shares together give the whole mesh's reference (stepScaleReference(shares)) at the cost of
  /// each piece's partitions, not the whole mesh's.
  struct StepScaleShare {
    std::vector<int64_t> sizeLog2Sums;
    std::vector<uint64_t> cellCounts;
  };
  StepScaleShare stepScaleShare(const Box3f &region, const Box3f &wholeBounds, uint32_t leafSize) const;
  static StepScaleReference stepScaleReference(const std::vector<StepScaleShare> &shares);
  /// The most cells per partition that kAutoLeafSize stands for.
  uint32_t defaultLeafSize() const;
  /// The partitions a renderer makes of this mesh with `leafSize` (kAutoLeafSize: the default); builds them.
  uint32_t partitionCount(uint32_t leafSize = kAutoLeafSize) const;

private:
  struct Impl;
  friend struct detail::Access;
  explicit VolumeMesh(std::shared_ptr<Impl> impl);
  std::shared_ptr<Impl> impl_;
};

/// What a partitioned .pvtu names: its pieces in order and, as `uvr convert --pieces` writes them, each
/// piece's region of space and the file of the cells it lacks there, and what renderers of the pieces take
/// from the whole mesh. Read without reading the pieces.
struct PartitionedFile {
  struct Piece {
    std::string path;   ///< its .vtu: the cells it owns (those whose box centres lie in its region)
    std::string ghosts; ///< a .vtu of the cells other pieces own whose boxes reach into its region; or empty
    Box3f region;       ///< empty where not written
  };
  std::vector<Piece> pieces;
  /// The whole mesh's, where written (cells 0 where not): cell count, bounds, VolumeMesh::defaultStep,
  /// volumeStats().median, defaultLeafSize and stepScaleReference for it, and each field's range.
  uint64_t cells = 0;
  Box3f bounds;
  float defaultStep = 0.f;
  double medianVolume = 0.0;
  uint32_t leafSize = 0;
  VolumeMesh::StepScaleReference stepScales;
  struct FieldRange {
    FieldInfo field;
    ValueRange range;
  };
  std::vector<FieldRange> fieldRanges;
};

/// Reads a .pvtu's list of pieces (see PartitionedFile). Throws uvr::Error where it is no .pvtu.
PartitionedFile readPartitionedFile(const std::string &path);

} // namespace uvr
