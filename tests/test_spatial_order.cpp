#include "mesh/mesh.h"
#include "mesh/mesh_stats.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

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
