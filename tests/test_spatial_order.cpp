#include "mesh/mesh.h"
#include "mesh/mesh_stats.h"
#include "mesh/procedural_mesh.h"

#include <uvr/error.h>
#include <uvr/mesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

using namespace uvr;

namespace {

float field(Vec3f p) { return 3.f * p.x - 2.f * p.y + 0.5f * p.z + 1.f; }

// Corners of each cell, as sets of coordinates, to compare meshes whatever their numbering.
std::multiset<std::vector<float>> cellCorners(const Mesh &mesh) {
  std::multiset<std::vector<float>> cells;
  for (size_t c = 0; c < mesh.tetCount(); ++c) {
    std::vector<float> corners;
    for (int i = 0; i < 4; ++i) {
      const Vec3f p = mesh.points[mesh.tets[4 * c + size_t(i)]];
      corners.insert(corners.end(), {p.x, p.y, p.z});
    }
    cells.insert(corners);
  }
  return cells;
}

// The cells shuffled as files often list them, each cell's field value (field 1) kept with it.
UnstructuredGrid scrambledCells(const UnstructuredGrid &grid) {
  const size_t count = grid.types.size();
  UnstructuredGrid scrambled = grid;
  scrambled.connectivity.clear();
  scrambled.offsets = {0};
  for (size_t i = 0; i < count; ++i) {
    const size_t c = (i * 7919) % count;
    for (int64_t k = grid.offsets[c]; k < grid.offsets[c + 1]; ++k)
      scrambled.connectivity.push_back(grid.connectivity[size_t(k)]);
    scrambled.offsets.push_back(int64_t(scrambled.connectivity.size()));
    scrambled.fields[1].values[i] = grid.fields[1].values[c];
  }
  return scrambled;
}

} // namespace

TEST(SpatialOrder, KeepsCellsAndFieldsAndImprovesLocality) {
  UnstructuredGrid grid = makeBoxGrid(CellType::Tetra, 12, {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}}, field, 0.2f);
  const UnstructuredGrid scrambled = scrambledCells(grid);

  Mesh unordered = buildMesh(UnstructuredGrid(scrambled), "scrambled");
  Mesh again = unordered;
  const Mesh lattice = buildMesh(std::move(grid), "lattice");
  EXPECT_EQ(cellCorners(unordered), cellCorners(lattice));

  // Point values still belong to their points, cell values to their cells.
  const int pointField = unordered.findField("f"), cellField = unordered.findField("f_cell");
  for (size_t v = 0; v < unordered.points.size(); ++v)
    EXPECT_NEAR(unordered.fields[size_t(pointField)].values[v], field(unordered.points[v]), 1e-4f);
  for (size_t c = 0; c < unordered.tetCount(); ++c) {
    Vec3f centroid{0.f, 0.f, 0.f};
    for (int i = 0; i < 4; ++i)
      centroid = centroid + unordered.points[unordered.tets[4 * c + size_t(i)]] * 0.25f;
    EXPECT_NEAR(unordered.fields[size_t(cellField)].values[c], field(centroid), 1e-4f);
  }

  // Consecutive cells lie close together: the mean centroid distance is a few cells, not a box width.
  double distance = 0.0;
  Vec3f previous{};
  for (size_t c = 0; c < unordered.tetCount(); ++c) {
    Vec3f centroid{0.f, 0.f, 0.f};
    for (int i = 0; i < 4; ++i)
      centroid = centroid + unordered.points[unordered.tets[4 * c + size_t(i)]] * 0.25f;
    if (c > 0)
      distance += std::sqrt(dot(centroid - previous, centroid - previous));
    previous = centroid;
  }
  EXPECT_LT(distance / double(unordered.tetCount() - 1), 2.0 / 12.0);

  // Ordering an ordered mesh again changes nothing.
  orderSpatially(again);
  EXPECT_EQ(again.tets, unordered.tets);
  EXPECT_EQ(again.fields[size_t(cellField)].values, unordered.fields[size_t(cellField)].values);
}

// Enough cells that the numbering splits them (see FirstUseNumbering::place): each corner is a point seen
// before or the next unseen one, and point values still belong to their points.
TEST(SpatialOrder, NumbersPointsByFirstUseInLargeMeshes) {
  const UnstructuredGrid grid =
      makeBoxGrid(CellType::Tetra, 26, {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}}, field, 0.2f);
  ASSERT_GT(grid.types.size(), size_t(1) << 16);
  const Mesh mesh = buildMesh(scrambledCells(grid), "scrambled");
  int64_t largest = -1;
  bool firstUseOrder = true;
  for (const uint32_t v : mesh.tets) {
    firstUseOrder &= int64_t(v) <= largest + 1;
    largest = std::max(largest, int64_t(v));
  }
  EXPECT_TRUE(firstUseOrder);
  EXPECT_EQ(largest + 1, int64_t(mesh.points.size()));
  const int pointField = mesh.findField("f");
  for (size_t v = 0; v < mesh.points.size(); ++v)
    ASSERT_NEAR(mesh.fields[size_t(pointField)].values[v], field(mesh.points[v]), 1e-4f);
}

// A selection keeps each type's chosen cells in their order with their corners and cell values, numbers the
// points they use (and no others) by first use with their values, and splits the numbering as a large mesh
// does.
TEST(SpatialOrder, SelectedCellsKeepOrderValuesAndFirstUseNumbering) {
  const Mesh mesh =
      buildMesh(makePyramidsAndTets(24, {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}}, field, 0.2f), "mixed");
  ASSERT_GT(mesh.pyramidCount(), size_t(1) << 16);
  ASSERT_GT(mesh.tetCount(), 0u);
  const int pointField = mesh.findField("f"), cellField = mesh.findField("f_cell");
  const auto cornersOf = [](const Mesh &m, const UninitVector<uint32_t> &cells, size_t c, size_t n) {
    std::vector<float> corners;
    for (size_t i = 0; i < n; ++i) {
      const Vec3f p = m.points[cells[c * n + i]];
      corners.insert(corners.end(), {p.x, p.y, p.z});
    }
    return corners;
  };
  std::vector<uint8_t> keep(mesh.cellCount());
  for (size_t c = 0; c < keep.size(); ++c)
    keep[c] = uint8_t(c % 7 != 3 && (c / 1000) % 3 != 1);
  const std::vector<int> fields = {cellField, pointField};
  const Mesh piece = selectCells(mesh, keep, fields);

  size_t first = 0, kept = 0;
  auto checkType = [&](const UninitVector<uint32_t> &from, const UninitVector<uint32_t> &to, size_t n) {
    const size_t count = from.size() / n;
    size_t out = 0;
    for (size_t c = 0; c < count; ++c) {
      if (!keep[first + c])
        continue;
      ASSERT_LT(out, to.size() / n);
      EXPECT_EQ(cornersOf(piece, to, out, n), cornersOf(mesh, from, c, n));
      EXPECT_EQ(piece.fields[0].values[kept + out], mesh.fields[size_t(cellField)].values[first + c]);
      ++out;
    }
    EXPECT_EQ(out, to.size() / n);
    first += count;
    kept += out;
  };
  checkType(mesh.tets, piece.tets, 4);
  checkType(mesh.pyramids, piece.pyramids, 5);
  EXPECT_EQ(piece.fields.size(), 2u);
  EXPECT_EQ(piece.fields[0].values.size(), piece.cellCount());
  EXPECT_EQ(piece.fields[1].centering, Centering::Point);

  int64_t largest = -1;
  bool firstUseOrder = true;
  for (const auto *cells : {&piece.tets, &piece.pyramids})
    for (const uint32_t v : *cells) {
      firstUseOrder &= int64_t(v) <= largest + 1;
      largest = std::max(largest, int64_t(v));
    }
  EXPECT_TRUE(firstUseOrder);
  EXPECT_EQ(largest + 1, int64_t(piece.points.size()));
  ASSERT_EQ(piece.fields[1].values.size(), piece.points.size());
  for (size_t v = 0; v < piece.points.size(); ++v)
    ASSERT_NEAR(piece.fields[1].values[v], field(piece.points[v]), 1e-4f);

  // Every cell: the mesh again; none: an empty one.
  const Mesh all = selectCells(mesh, std::vector<uint8_t>(mesh.cellCount(), 1), fields);
  EXPECT_EQ(all.tets, mesh.tets);
  EXPECT_EQ(all.pyramids, mesh.pyramids);
  EXPECT_EQ(all.points.size(), mesh.points.size());
  const Mesh none = selectCells(mesh, std::vector<uint8_t>(mesh.cellCount(), 0), fields);
  EXPECT_EQ(none.cellCount(), 0u);
  EXPECT_TRUE(none.points.empty());
}

TEST(SpatialOrder, VolumeMeshSelectionChecksItsArguments) {
  const VolumeMesh mesh = VolumeMesh::load(std::string(UVR_TEST_DATA) + "/../../data/disk_out_ref.vtu");
  std::vector<uint8_t> keep(mesh.cellCount(), 0);
  std::fill(keep.begin(), keep.begin() + ptrdiff_t(keep.size() / 2), uint8_t(1));
  const VolumeMesh half = mesh.selectCells(keep, {1, 0});
  EXPECT_EQ(half.cellCount(), keep.size() / 2);
  ASSERT_EQ(half.fieldCount(), 2);
  EXPECT_EQ(half.field(0).name, mesh.field(1).name);
  EXPECT_EQ(half.source(), mesh.source());
  keep.pop_back();
  EXPECT_THROW(mesh.selectCells(keep, {0}), Error);
  keep.push_back(1);
  EXPECT_THROW(mesh.selectCells(keep, {mesh.fieldCount()}), Error);
}
