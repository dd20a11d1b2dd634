#include "mesh/mesh.h"

#include "core/parallel_bounds.h"
#include "mesh/spatial_order.h"
#include <uvr/error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace uvr {

namespace {

/// Which kept type a VTK cell becomes, and which of its points are the corners. Higher-order cells keep
/// their corner nodes, which VTK lists first.
struct CellKind {
  CellType type;
  int corners;
};

bool volumeKind(uint8_t vtkType, CellKind &kind) {
  switch (vtkType) {
  case 10: // tetra
  case 24: // quadratic tetra
    kind = {CellType::Tetra, 4};
    return true;
  case 11: // voxel: a hexahedron with another point order, fixed in addCell
  case 12: // hexahedron
  case 25: // quadratic hexahedron
  case 29: // triquadratic hexahedron
  case 33: // biquadratic-quadratic hexahedron
    kind = {CellType::Hexahedron, 8};
    return true;
  case 13: // wedge
  case 26: // quadratic wedge
  case 31: // quadratic-linear wedge
  case 32: // biquadratic-quadratic wedge
    kind = {CellType::Wedge, 6};
    return true;
  case 14: // pyramid
  case 27: // quadratic pyramid
    kind = {CellType::Pyramid, 5};
    return true;
  default:
    return false;
  }
}

/// VTK's 0-, 1- and 2-dimensional cell types (linear, quadratic, Lagrange, Bezier), skipped by a volume
/// renderer.
bool lowerDimensional(uint8_t vtkType) {
  constexpr uint8_t kTypes[] = {
      1,  2,  3,  4,  5,  6,  7,  8,  9, // vertex .. quad
      21, 22, 23, 28, 30, 34, 35, 36,    // quadratic edge .. quadratic polygon
      68, 69, 70, 75, 76, 77,            // Lagrange and Bezier curves, triangles, quads
  };
  return std::find(std::begin(kTypes), std::end(kTypes), vtkType) != std::end(kTypes);
}

float orientedVolume(Vec3f a, Vec3f b, Vec3f c, Vec3f d) { return dot(b - a, cross(c - a, d - a)); }

/// Positive for cells wound as VTK expects. Hexahedra and pyramids by the Jacobian at the centre; VTK's wedge
/// base (0,1,2) faces away from the top, hence its sign.
float windingSign(CellType type, const uint32_t *v, std::span<const Vec3f> p) {
  switch (type) {
  case CellType::Tetra:
    return orientedVolume(p[v[0]], p[v[1]], p[v[2]], p[v[3]]);
  case CellType::Pyramid: {
    const Vec3f base = (p[v[0]] + p[v[1]] + p[v[2]] + p[v[3]]) * 0.25f;
    return dot(cross(p[v[2]] - p[v[0]], p[v[3]] - p[v[1]]), p[v[4]] - base);
  }
  case CellType::Wedge: {
    const Vec3f bottom = (p[v[0]] + p[v[1]] + p[v[2]]) / 3.f;
    const Vec3f top = (p[v[3]] + p[v[4]] + p[v[5]]) / 3.f;
    return -dot(cross(p[v[1]] - p[v[0]], p[v[2]] - p[v[0]]), top - bottom);
  }
  case CellType::Hexahedron: {
    auto average = [&](int a0, int a1, int b0, int b1, int c0, int c1, int d0, int d1) {
      return (p[v[a1]] - p[v[a0]]) + (p[v[b1]] - p[v[b0]]) + (p[v[c1]] - p[v[c0]]) + (p[v[d1]] - p[v[d0]]);
    };
    const Vec3f dr = average(0, 1, 3, 2, 4, 5, 7, 6);
    const Vec3f ds = average(0, 3, 1, 2, 4, 7, 5, 6);
    const Vec3f dt = average(0, 4, 1, 5, 2, 6, 3, 7);
    return dot(dr, cross(ds, dt));
  }
  }
  return 0.f;
}

/// Mirrors a cell: the same shape, the opposite winding.
void reverseWinding(CellType type, uint32_t *v) {
  switch (type) {
  case CellType::Tetra:
    std::swap(v[1], v[2]);
    break;
  case CellType::Pyramid:
    std::swap(v[1], v[3]);
    break;
  case CellType::Wedge:
    for (int i = 0; i < 3; ++i)
      std::swap(v[i], v[i + 3]);
    break;
  case CellType::Hexahedron:
    for (int i = 0; i < 4; ++i)
      std::swap(v[i], v[i + 4]);
    break;
  }
}

/// Which of Mesh's type arrays (tets, pyramids, wedges, hexahedra) a volume cell type goes to.
int slotOf(CellType type) {
  switch (type) {
  case CellType::Tetra:
    return 0;
  case CellType::Pyramid:
    return 1;
  case CellType::Wedge:
    return 2;
  case CellType::Hexahedron:
    return 3;
  }
  return 0;
}

/// The cell's point count, when its offsets do not decrease. Unsigned, as a chunk checked in parallel may
/// start past an earlier chunk's bad offsets.
template <typename Index> bool pointCount(const CellArrays<Index> &grid, size_t c, uint64_t &count) {
  count = uint64_t(grid.offsets[c + 1]) - uint64_t(grid.offsets[c]);
  return grid.offsets[c + 1] >= grid.offsets[c];
}

/// Whether buildMesh can take cell c: offsets that do not decrease, and a volume cell with points for all of
/// its corners or a lower-dimensional one (skipped).
template <typename Index> bool wellFormed(const CellArrays<Index> &grid, size_t c) {
  uint64_t count;
  if (!pointCount(grid, c, count))
    return false;
  CellKind kind;
  if (volumeKind(grid.types[c], kind))
    return count >= uint64_t(kind.corners);
  return lowerDimensional(grid.types[c]);
}

/// Says why cell c is not wellFormed.
template <typename Index>
[[noreturn]] void throwMalformed(const CellArrays<Index> &grid, size_t c, const std::string &source) {
  const std::string cell = "cell " + std::to_string(c);
  const uint8_t vtkType = grid.types[c];
  uint64_t count;
  if (!pointCount(grid, c, count))
    throw Error(source, cell, "cell offsets decrease");
  CellKind kind;
  if (volumeKind(vtkType, kind))
    throw Error(source, cell,
                "cell of VTK type " + std::to_string(vtkType) + " needs " + std::to_string(kind.corners) +
                    " points, has " + std::to_string(count));
  throw Error(source, cell, "unsupported VTK cell type " + std::to_string(vtkType));
}

/// Whether a point index lies outside [0, pointCount); a negative one wraps to 2^63 or more.
template <typename Index> bool outside(Index id, uint64_t pointCount) {
  return uint64_t(int64_t(id)) >= pointCount;
}

/// orientCell's body, always inlined: a loop over one type's cells, passing that type as a constant, is
/// compiled for that type's arithmetic alone.
[[gnu::always_inline]] inline bool orientInline(CellType type, uint32_t *v, std::span<const Vec3f> points) {
  if (windingSign(type, v, points) >= 0.f)
    return false;
  reverseWinding(type, v);
  return true;
}

constexpr CellKind kSlotKinds[4] = {
    {CellType::Tetra, 4}, {CellType::Pyramid, 5}, {CellType::Wedge, 6}, {CellType::Hexahedron, 8}};

} // namespace

bool orientCell(CellType type, uint32_t *v, std::span<const Vec3f> points) {
  return orientInline(type, v, points);
}

int vertexCount(uint8_t vtkType) {
  CellKind kind;
  return volumeKind(vtkType, kind) ? kind.corners : 0;
}

Box3f Mesh::bounds() const {
  return parallelBounds(points.size(), [&](uint64_t i) { return points[i]; });
}

int Mesh::findField(const std::string &name) const {
  auto first = [&](std::string_view wanted, std::optional<Centering> centering) {
    for (size_t i = 0; i < fields.size(); ++i)
      if (fields[i].name == wanted && (!centering || fields[i].centering == *centering))
        return int(i);
    return -1;
  };
  // "point:p" and "cell:p" say which of two fields named p; a field whose own name has that prefix is found
  // when no field of that centring is.
  for (auto [prefix, centering] : {std::pair{std::string_view("point:"), Centering::Point},
                                   std::pair{std::string_view("cell:"), Centering::Cell}})
    if (name.starts_with(prefix))
      if (const int index = first(std::string_view(name).substr(prefix.size()), centering); index >= 0)
        return index;
  // A plain name: the point field where a file has both, whatever order its format lists them in.
  const int point = first(name, Centering::Point);
  return point >= 0 ? point : first(name, std::nullopt);
}

namespace {

/// A mesh's cells before they are wound and ordered: each volume type's corners back to back, 32-bit point
/// indices, in the order tets, pyramids, wedges, hexahedra (Mesh's).
struct TypeArrays {
  std::array<Buffer<uint32_t>, 4> cells;
  std::array<uint64_t, 4> counts{};
  std::array<Buffer<uint64_t>, 4> keys; ///< room for each type's sort keys, where it is already at hand
};

template <typename Index> void checkSpan(const CellArrays<Index> &grid, const std::string &source) {
  const size_t cellCount = grid.types.size();
  if (grid.offsets.size() != cellCount + 1)
    throw Error(source, "", "cell offsets and cell types disagree in count");
  if (grid.offsets[0] != 0 || uint64_t(grid.offsets[cellCount]) > grid.connectivity.size())
    throw Error(source, "", "cell offsets do not span the connectivity array");
}

/// Says that point index `bad` of cell c lies outside the points.
template <typename Index>
[[noreturn]] void throwOutside(size_t c, Index bad, uint64_t pointCount, const std::string &source) {
  throw Error(source, "cell " + std::to_string(c),
              "point index " + std::to_string(bad) + " outside [0, " + std::to_string(pointCount) + ")");
}

/// Says which point index of cell c lies outside the points.
template <typename Index>
[[noreturn]] void throwOutside(const CellArrays<Index> &grid, size_t c, uint64_t pointCount,
                               const std::string &source) {
  const Index *ids = &grid.connectivity[size_t(grid.offsets[c])];
  throwOutside(
      c,
      *std::find_if(ids, ids + vertexCount(grid.types[c]), [&](Index id) { return outside(id, pointCount); }),
      pointCount, source);
}

void checkPointCount(size_t pointCount, const std::string &source) {
  if (pointCount > UINT32_MAX)
    throw Error(source, "", "more than 2^32 points are not supported");
}

/// Cell fields one value per cell of the file, point fields one per point.
void checkFieldSizes(const std::vector<ScalarField> &fields, size_t cellCount, size_t pointCount,
                     const std::string &source) {
  for (const ScalarField &field : fields) {
    if (field.centering == Centering::Cell && field.values.size() != cellCount)
      throw Error(source, "",
                  "cell field '" + field.name + "' has " + std::to_string(field.values.size()) +
                      " values for " + std::to_string(cellCount) + " cells");
    if (field.centering == Centering::Point && field.values.size() != pointCount)
      throw Error(source, "",
                  "point field '" + field.name + "' has " + std::to_string(field.values.size()) +
                      " values for " + std::to_string(pointCount) + " points");
  }
}

/// The mesh from its points, its cells grouped by type and its fields with cell values in type order: the
/// cells wound, each type's ordered along the Morton curve, the points numbered by first use. Checks the
/// cells' point indices and then the fields' sizes, as groupAndBuild does, in that order; a cell is named by
/// its index in its type array, which for cells of one type back to back is the file's.
Mesh windAndOrder(UninitVector<Vec3f> &&points, TypeArrays &&types, std::vector<ScalarField> &&fields,
                  uint64_t skippedCells, const std::string &source) {
  Mesh mesh;
  mesh.skippedCells = skippedCells;
  mesh.points = std::move(points);
  const CellKeys cellKeys(mesh.bounds());
  const std::array<uint64_t, 4> &perType = types.counts;
  const std::array<uint64_t, 4> firstCell = {0, perType[0], perType[0] + perType[1],
                                             perType[0] + perType[1] + perType[2]};
  const uint64_t keptCells = firstCell[3] + perType[3];

  // Winding and keys in a pass over each type array. Files seldom list cells in spatial order, so the
  // corners' points are loaded from all over memory: the loop asks for those of a later cell early (by an
  // address computed as an integer: the index is checked only when its cell comes). The point indices are
  // checked here, in the pass that loads the corners anyway, not in one of their own.
  std::array<Buffer<uint64_t>, 4> &typeKeys = types.keys;
  const auto pointCount = uint32_t(mesh.points.size());
  const auto pointsAddress = reinterpret_cast<uintptr_t>(mesh.points.data());
  struct Wound {
    uint64_t inverted = 0;
    size_t firstOutside = SIZE_MAX; ///< the first cell with a point index outside the points
  };
  std::array<Wound, 4> wound;
  auto windAndKey = [&]<CellType Type, int Corners>(size_t s) {
    constexpr size_t kPrefetchCells = 16;
    if (typeKeys[s].size() != perType[s])
      typeKeys[s] = Buffer<uint64_t>(perType[s]);
    wound[s] = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, perType[s], 1 << 12), Wound{},
        [&](const tbb::blocked_range<size_t> &r, Wound w) {
          for (size_t c = r.begin(); c < r.end(); ++c) {
            uint32_t *v = types.cells[s].data() + c * Corners;
            if (c + kPrefetchCells < r.end())
              for (int i = 0; i < Corners; ++i)
                __builtin_prefetch(reinterpret_cast<const void *>(
                    pointsAddress + v[kPrefetchCells * Corners + i] * sizeof(Vec3f)));
            unsigned outside = 0;
            for (int i = 0; i < Corners; ++i)
              outside |= unsigned(v[i] >= pointCount);
            if (outside != 0) {
              w.firstOutside = std::min(w.firstOutside, c);
              continue;
            }
            w.inverted += orientInline(Type, v, mesh.points);
            typeKeys[s][c] = cellKeys.key(v, Corners, mesh.points, c);
          }
          return w;
        },
        [](Wound a, Wound b) {
          return Wound{a.inverted + b.inverted, std::min(a.firstOutside, b.firstOutside)};
        });
  };
  windAndKey.template operator()<CellType::Tetra, 4>(0);
  windAndKey.template operator()<CellType::Pyramid, 5>(1);
  windAndKey.template operator()<CellType::Wedge, 6>(2);
  windAndKey.template operator()<CellType::Hexahedron, 8>(3);
  for (size_t s = 0; s < 4; ++s) {
    if (wound[s].firstOutside != SIZE_MAX) {
      const size_t c = wound[s].firstOutside;
      const auto corners = size_t(kSlotKinds[s].corners);
      const uint32_t *v = types.cells[s].data() + c * corners;
      throwOutside(c, *std::find_if(v, v + corners, [&](uint32_t id) { return id >= pointCount; }),
                   pointCount, source);
    }
    mesh.invertedCells += wound[s].inverted;
  }
  checkFieldSizes(fields, keptCells, mesh.points.size(), source);

  std::array<Buffer<uint32_t>, 4> orders;
  for (size_t s = 0; s < 4; ++s)
    orders[s] = sortedOrder(typeKeys[s]);
  // The cell fields before the cells: placing the cells takes one thread for each half of them (see
  // FirstUseNumbering), and a gather beside them would hold up one half while the other thread waits.
  for (ScalarField &field : fields) {
    if (field.centering == Centering::Cell) {
      UninitVector<float> sorted(keptCells);
      for (size_t s = 0; s < 4; ++s)
        gather<1>(sorted.data() + firstCell[s], field.values.data() + firstCell[s], perType[s], orders[s]);
      field.values = std::move(sorted);
    }
  }
  FirstUseNumbering numbering(mesh.points.size());
  auto placeCells = [&]<size_t Corners>(size_t s, UninitVector<uint32_t> &cells) {
    cells.resize(perType[s] * Corners);
    numbering.place<Corners>(cells.data(), types.cells[s].data(), perType[s], orders[s]);
  };
  placeCells.template operator()<4>(0, mesh.tets);
  placeCells.template operator()<5>(1, mesh.pyramids);
  placeCells.template operator()<6>(2, mesh.wedges);
  placeCells.template operator()<8>(3, mesh.hexes);
  mesh.fields = std::move(fields);
  numbering.reorderPoints(mesh);
  return mesh;
}

/// Groups cells of any types by type, in two parallel passes over chunks of cells: the first checks the cells
/// and counts each chunk's cells of each type, which says where the second writes them (and the cell field
/// values, in type order in place of the file's). Errors name the first bad cell in file order, as a serial
/// pass would.
template <typename Index>
Mesh groupAndBuild(UninitVector<Vec3f> &&points, CellArrays<Index> grid, std::vector<ScalarField> &&fields,
                   const std::string &source) {
  const size_t cellCount = grid.types.size();
  checkSpan(grid, source);
  constexpr size_t kChunkCells = size_t(1) << 14;
  struct Chunk {
    std::array<uint64_t, 4> perType{}; ///< in pass 2: the chunk's first cell of each type, within its type
    uint64_t skipped = 0;
    size_t firstMalformed = SIZE_MAX;
    size_t firstBadIndex = SIZE_MAX;
  };
  std::vector<Chunk> chunks((cellCount + kChunkCells - 1) / kChunkCells);
  auto forEachChunk = [&](auto &&body) {
    tbb::parallel_for(size_t(0), chunks.size(), [&](size_t k) {
      body(chunks[k], k * kChunkCells, std::min(cellCount, (k + 1) * kChunkCells));
    });
  };

  forEachChunk([&](Chunk &chunk, size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      CellKind kind;
      if (!wellFormed(grid, c)) {
        chunk.firstMalformed = c;
        return;
      }
      if (volumeKind(grid.types[c], kind))
        ++chunk.perType[slotOf(kind.type)];
      else
        ++chunk.skipped;
    }
  });
  TypeArrays types;
  std::array<uint64_t, 4> &perType = types.counts;
  uint64_t skippedCells = 0;
  for (Chunk &chunk : chunks) {
    if (chunk.firstMalformed != SIZE_MAX)
      throwMalformed(grid, chunk.firstMalformed, source);
    for (size_t s = 0; s < 4; ++s)
      perType[s] += std::exchange(chunk.perType[s], perType[s]);
    skippedCells += chunk.skipped;
  }
  checkPointCount(points.size(), source);

  const std::array<uint64_t, 4> firstCell = {0, perType[0], perType[0] + perType[1],
                                             perType[0] + perType[1] + perType[2]};
  const uint64_t keptCells = firstCell[3] + perType[3];
  for (size_t s = 0; s < 4; ++s)
    types.cells[s] = Buffer<uint32_t>(perType[s] * uint64_t(kSlotKinds[s].corners));
  // A cell field of the wrong size is reported below, after the cells.
  std::vector<UninitVector<float>> typeOrderValues(fields.size());
  for (size_t f = 0; f < fields.size(); ++f)
    if (fields[f].centering == Centering::Cell && fields[f].values.size() == cellCount)
      typeOrderValues[f].resize(keptCells);

  forEachChunk([&](Chunk &chunk, size_t begin, size_t end) {
    std::array<uint64_t, 4> next = chunk.perType;
    for (size_t c = begin; c < end; ++c) {
      CellKind kind;
      if (!volumeKind(grid.types[c], kind))
        continue;
      const int s = slotOf(kind.type);
      uint32_t *v = types.cells[s].data() + next[s] * uint64_t(kind.corners);
      const Index *ids = &grid.connectivity[size_t(grid.offsets[c])];
      for (int i = 0; i < kind.corners; ++i) {
        if (outside(ids[i], points.size())) {
          chunk.firstBadIndex = c;
          return;
        }
        v[i] = uint32_t(ids[i]);
      }
      if (grid.types[c] == 11) { // voxel corners run in x-fastest lattice order
        std::swap(v[2], v[3]);
        std::swap(v[6], v[7]);
      }
      for (size_t f = 0; f < fields.size(); ++f)
        if (!typeOrderValues[f].empty())
          typeOrderValues[f][firstCell[s] + next[s]] = fields[f].values[c];
      ++next[s];
    }
  });
  for (const Chunk &chunk : chunks)
    if (chunk.firstBadIndex != SIZE_MAX)
      throwOutside(grid, chunk.firstBadIndex, points.size(), source);
  checkFieldSizes(fields, cellCount, points.size(), source);
  for (size_t f = 0; f < fields.size(); ++f)
    if (fields[f].centering == Centering::Cell)
      fields[f].values = std::move(typeOrderValues[f]);
  return windAndOrder(std::move(points), std::move(types), std::move(fields), skippedCells, source);
}

/// The slot of the one linear volume type of all cells, when they lie back to back in the connectivity (cell
/// c's corners from entry c * corners on): the connectivity is then that type's cell array as it is, and the
/// cells are in type order (windAndOrder checks their point indices). -1 otherwise.
int backToBackSlot(const CellArrays<uint32_t> &grid) {
  const size_t cellCount = grid.types.size();
  CellKind kind;
  // The type code must be the kept type's own: voxels' corners are reordered, higher-order cells have more
  // points than corners.
  if (cellCount == 0 || !volumeKind(grid.types[0], kind) || uint8_t(kind.type) != grid.types[0])
    return -1;
  const uint8_t type = grid.types[0];
  const auto corners = uint64_t(kind.corners);
  if (uint64_t(grid.offsets[cellCount]) != cellCount * corners) // else the connectivity may be shorter
    return -1;
  std::atomic<bool> backToBack = true;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, cellCount, size_t(1) << 16),
                    [&](const tbb::blocked_range<size_t> &r) {
                      if (!backToBack.load(std::memory_order_relaxed))
                        return;
                      // Without early exits, and or-ing unsigned differences where a bool's &= or a 64-bit
                      // == would not vectorise.
                      unsigned mismatch = 0;
                      for (size_t c = r.begin(); c < r.end(); ++c)
                        mismatch |= unsigned(grid.types[c] != type);
                      uint64_t offsetDifference = 0, end = (r.begin() + 1) * corners;
                      for (size_t c = r.begin(); c < r.end(); ++c, end += corners)
                        offsetDifference |= uint64_t(grid.offsets[c + 1]) ^ end;
                      if (mismatch != 0 || offsetDifference != 0)
                        backToBack.store(false, std::memory_order_relaxed);
                    });
  return backToBack ? slotOf(kind.type) : -1;
}

} // namespace

void checkPoints(std::span<const Vec3f> points, const std::string &source) {
  const size_t n = points.size();
  const size_t bad = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 1 << 16), n,
      [&](const tbb::blocked_range<size_t> &r, size_t least) {
        for (size_t i = r.begin(); i < r.end() && i < least; ++i)
          if (!(std::isfinite(points[i].x) && std::isfinite(points[i].y) && std::isfinite(points[i].z)))
            return i;
        return least;
      },
      [](size_t a, size_t b) { return std::min(a, b); });
  if (bad < n)
    throw Error(source, "point " + std::to_string(bad), "coordinates are not finite");
}

Mesh buildMesh(UnstructuredGrid &&grid, const std::string &source) {
  Mesh mesh = buildMesh(std::move(grid.points), CellArraysView{grid.offsets, grid.connectivity, grid.types},
                        std::move(grid.fields), source);
  mesh.polyhedra = grid.polyhedra;
  return mesh;
}

Mesh buildMesh(UninitVector<Vec3f> &&points, CellArraysView cells, std::vector<ScalarField> &&fields,
               const std::string &source) {
  checkPoints(points, source);
  return groupAndBuild(std::move(points), cells, std::move(fields), source);
}

Mesh buildMesh(UninitVector<Vec3f> &&points, CellBuffers &&cells, std::vector<ScalarField> &&fields,
               const std::string &source) {
  checkPoints(points, source);
  const CellArrays<uint32_t> grid = cells.view();
  const size_t cellCount = grid.types.size();
  checkSpan(grid, source);
  const int slot = points.size() <= UINT32_MAX ? backToBackSlot(grid) : -1;
  if (slot < 0)
    return groupAndBuild(std::move(points), grid, std::move(fields), source);
  TypeArrays types;
  types.cells[size_t(slot)] = std::move(cells.connectivity);
  types.counts[size_t(slot)] = cellCount;
  // The offsets are done with, and one longer than the keys.
  types.keys[size_t(slot)] = std::move(cells.offsets).reuseAs<uint64_t>(cellCount);
  return windAndOrder(std::move(points), std::move(types), std::move(fields), 0, source);
}

} // namespace uvr
