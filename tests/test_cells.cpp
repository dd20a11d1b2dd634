// Point location and interpolation inside single cells, and mesh construction.
#include "mesh/cell.h"
#include "mesh/mesh_stats.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_affine.h"
#include <uvr/error.h>

#include <gtest/gtest.h>

#include <random>

using namespace uvr;

namespace {

float linear(Vec3f p) { return 0.5f + 2.f * p.x - 3.f * p.y + 1.5f * p.z; }

const Box3f kUnitBox{{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}};

/// A jittered box mesh of one cell type with the linear field.
Mesh jitteredMesh(CellType type) {
  return buildMesh(makeBoxGrid(type, 3, kUnitBox, linear, 0.2f, 7), "test");
}

class EveryCellType : public ::testing::TestWithParam<CellType> {};

} // namespace

TEST(TetWeights, LinearFieldIsExactInside) {
  const Vec3f a{0.1f, 0.2f, 0.3f}, b{1.3f, 0.1f, 0.2f}, c{0.4f, 1.2f, 0.1f}, d{0.5f, 0.4f, 1.1f};
  std::mt19937 random(3);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 1000; ++i) {
    float l[4] = {u(random), u(random), u(random), u(random)};
    const float sum = l[0] + l[1] + l[2] + l[3];
    const Vec3f p = (a * l[0] + b * l[1] + c * l[2] + d * l[3]) / sum;
    float w[4];
    ASSERT_TRUE(tetWeights(a, b, c, d, p, w));
    const float value = w[0] * linear(a) + w[1] * linear(b) + w[2] * linear(c) + w[3] * linear(d);
    EXPECT_NEAR(value, linear(p), 1e-5f);
  }
  float w[4];
  EXPECT_FALSE(tetWeights(a, b, c, d, {2.f, 2.f, 2.f}, w));
  EXPECT_TRUE(tetWeights(a, b, c, d, a, w));
  EXPECT_NEAR(w[0], 1.f, 1e-6f);
}

// The weights' change along a direction predicts the weights of points further along it.
TEST(TetWeights, ChangeAlongADirectionIsTheWeightsDifference) {
  const Vec3f a{0.1f, 0.2f, 0.3f}, b{1.3f, 0.1f, 0.2f}, c{0.4f, 1.2f, 0.1f}, d{0.5f, 0.4f, 1.1f};
  std::mt19937 random(5);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int i = 0; i < 1000; ++i) {
    const Vec3f p{u(random), u(random), u(random)}, direction{u(random), u(random), u(random)};
    const float s = u(random);
    float w[4], dw[4], ahead[4], plain[4];
    ASSERT_TRUE(tetBarycentricsAlong(a, b, c, d, p, direction, w, dw));
    ASSERT_TRUE(tetBarycentrics(a, b, c, d, p + direction * s, ahead));
    ASSERT_TRUE(tetBarycentrics(a, b, c, d, p, plain));
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(w[k], plain[k]);
      EXPECT_NEAR(w[k] + s * dw[k], ahead[k], 1e-5f);
    }
  }
}

// A tet's affine record gives the weights and their change along a direction that its corners give, and the
// value they interpolate, also far from the origin; a flat tet has none.
TEST(TetAffine, AgreesWithTheCorners) {
  std::mt19937 random(9);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (const Vec3f offset : {Vec3f{0.f, 0.f, 0.f}, Vec3f{3000.f, -2000.f, 500.f}}) {
    const Vec3f corners[8] = {offset + Vec3f{0.1f, 0.2f, 0.3f}, offset + Vec3f{1.3f, 0.1f, 0.2f},
                              offset + Vec3f{0.4f, 1.2f, 0.1f}, offset + Vec3f{0.5f, 0.4f, 1.1f},
                              offset + Vec3f{0.6f, 0.6f, 0.6f}, offset + Vec3f{1.6f, 0.6f, 0.6f},
                              offset + Vec3f{0.6f, 1.6f, 0.6f}, offset + Vec3f{1.1f, 1.1f, 0.6f}};
    const uint32_t tets[8] = {0, 1, 2, 3, 4, 5, 6, 7}; // the second is flat
    float values[8];
    for (int k = 0; k < 8; ++k)
      values[k] = linear(corners[k] - offset);
    MeshView view;
    view.points = corners;
    view.tets = tets;
    view.tetCount = 2;
    view.values = values;
    const std::vector<TetAffine> records = buildTetAffine(view);
    ASSERT_EQ(records.size(), 2u);
    const Vec3f *c = corners;
    for (int i = 0; i < 200; ++i) {
      const Vec3f p = offset + Vec3f{u(random), u(random), u(random)};
      const Vec3f direction{u(random), u(random), u(random)};
      float w[4], dw[4], expected[4], expectedChange[4];
      ASSERT_TRUE(tetBarycentricsAlong(c[0], c[1], c[2], c[3], p, direction, expected, expectedChange));
      float value, slope;
      ASSERT_TRUE(records[0].along(p, direction, w, dw, value, slope));
      for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(w[k], expected[k], 1e-5f);
        EXPECT_NEAR(dw[k], expectedChange[k], 1e-5f);
      }
      EXPECT_NEAR(value, linear(p - offset), 1e-4f);
      EXPECT_NEAR(slope, linear(direction) - linear({}), 1e-4f);
      EXPECT_FALSE(records[1].along(p, direction, w, dw, value, slope));
    }
  }
}

TEST_P(EveryCellType, ShapeFunctionsReproduceVertexValues) {
  const Mesh mesh = jitteredMesh(GetParam());
  const MeshView view = makeMeshView(mesh, mesh.findField("f"));
  for (uint64_t cell = 0; cell < view.cellCount(); ++cell)
    forEachCellVertex(view, cell, [&](uint32_t v) {
      float value;
      ASSERT_TRUE(sampleCell(view, cell, mesh.points[v], value)) << "cell " << cell << " vertex " << v;
      EXPECT_NEAR(value, view.values[v], 1e-4f);
    });
}

TEST_P(EveryCellType, ShapeFunctionsReproduceLinearFields) {
  const Mesh mesh = jitteredMesh(GetParam());
  const MeshView view = makeMeshView(mesh, mesh.findField("f"));
  std::mt19937 random(11);
  std::uniform_real_distribution<float> u(0.02f, 0.98f);
  int found = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3f p{u(random), u(random), u(random)};
    int holders = 0;
    for (uint64_t cell = 0; cell < view.cellCount(); ++cell) {
      float value;
      if (sampleCell(view, cell, p, value)) {
        ++holders;
        EXPECT_NEAR(value, linear(p), 2e-4f) << "cell " << cell;
      }
    }
    // The cells tile the box: every point lies in one cell (or on a shared face, in a few).
    EXPECT_GE(holders, 1);
    found += holders;
  }
  EXPECT_LT(found, 2000 * 2);
}

TEST_P(EveryCellType, CellDataIsTheCellsValue) {
  const Mesh mesh = jitteredMesh(GetParam());
  const MeshView view = makeMeshView(mesh, mesh.findField("f_cell"));
  for (uint64_t cell = 0; cell < view.cellCount(); ++cell) {
    Vec3f centroid{};
    int n = 0;
    forEachCellVertex(view, cell, [&](uint32_t v) { centroid = centroid + mesh.points[v], ++n; });
    float value;
    ASSERT_TRUE(sampleCell(view, cell, centroid / float(n), value));
    EXPECT_EQ(value, view.values[cell]);
  }
}

TEST_P(EveryCellType, VolumesSumToTheBox) {
  const Mesh mesh = jitteredMesh(GetParam());
  const MeshView view = makeMeshView(mesh, -1);
  double total = 0.0;
  for (uint64_t cell = 0; cell < view.cellCount(); ++cell)
    total += cellVolume(view, cell);
  EXPECT_NEAR(total, 1.0, 1e-4);
  EXPECT_EQ(mesh.invertedCells, 0u);
}

// A walk's solve (RaySolve) starts from the last sample's coordinates carried along the ray: it must reach
// the root a cold start from the centre reaches, and the rate it hands on must be the coordinates' change
// along the ray. Points outside the cell keep coordinates that name the face they lie beyond.
TEST(ParametricCoordinates, WarmStartsReachTheColdRootAndTheRateFollowsTheRay) {
  const Mesh mesh = jitteredMesh(CellType::Hexahedron);
  const MeshView view = makeMeshView(mesh, mesh.findField("f"));
  std::mt19937 random(5);
  std::uniform_real_distribution<float> u(0.05f, 0.95f), nudge(-0.3f, 0.3f);
  const Vec3f direction = normalize(Vec3f{0.3f, -0.5f, 0.8f});
  const float h = 1e-3f;
  int faces = 0;
  for (uint64_t cell = 0; cell < view.hexCount; ++cell) {
    const uint32_t *v = view.hexes + 8 * cell;
    for (int i = 0; i < 20; ++i) {
      const Vec3f inside{u(random), u(random), u(random)};
      ShapeFunctions<8> s;
      evaluateShape(inside, s);
      Vec3f p{};
      for (int k = 0; k < 8; ++k)
        p = p + view.points[v[k]] * s.value[k];
      Vec3f cold, warm, ahead;
      ASSERT_TRUE(parametricCoordinates<8>(view.points, v, p, cold));
      EXPECT_NEAR(length(cold - inside), 0.f, 1e-4f);
      RaySolve along;
      along.direction = direction;
      along.warm = true;
      along.start = inside + Vec3f{nudge(random), nudge(random), nudge(random)};
      ASSERT_TRUE(parametricCoordinates<8>(view.points, v, p, warm, &along));
      EXPECT_NEAR(length(warm - cold), 0.f, 1e-4f);
      ASSERT_TRUE(parametricCoordinates<8>(view.points, v, p + direction * h, ahead));
      EXPECT_NEAR(length((ahead - cold) / h - along.rate), 0.f, 0.02f * length(along.rate));

      // A point a third of the cell beyond face f (cellFaces' order: x = 0, x = 1, y = 0, ...).
      const int f = i % 6;
      Vec3f beyondFace = inside;
      (f < 2 ? beyondFace.x : f < 4 ? beyondFace.y : beyondFace.z) = f % 2 ? 1.33f : -0.33f;
      evaluateShape(beyondFace, s);
      Vec3f q{};
      for (int k = 0; k < 8; ++k)
        q = q + view.points[v[k]] * s.value[k];
      RaySolve walk;
      walk.direction = direction;
      walk.anywhere = true;
      Vec3f r;
      parametricCoordinates<8>(view.points, v, q, r, &walk);
      float most;
      faces += hexFaceBeyond(r, most) == f && most > 0.f;
    }
  }
  // One Newton step from the centre, where the point lies outside the cell's box, can misjudge which face a
  // point near an edge of a jittered cell lies beyond; seldom.
  EXPECT_GT(faces, int(0.95 * 20 * view.hexCount)) << faces << " of " << 20 * view.hexCount;
}

INSTANTIATE_TEST_SUITE_P(Cells, EveryCellType,
                         ::testing::Values(CellType::Tetra, CellType::Hexahedron, CellType::Wedge,
                                           CellType::Pyramid),
                         [](const auto &info) {
                           switch (info.param) {
                           case CellType::Tetra:
                             return std::string("Tetra");
                           case CellType::Hexahedron:
                             return std::string("Hexahedron");
                           case CellType::Wedge:
                             return std::string("Wedge");
                           default:
                             return std::string("Pyramid");
                           }
                         });

TEST(BuildMesh, SkipsLowerDimensionalCellsAndReordersCellData) {
  UnstructuredGrid grid;
  grid.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  grid.offsets = {0, 3, 8, 12};
  grid.connectivity = {0, 1, 2, /*pyramid*/ 0, 1, 4, 2, 3, /*tet*/ 0, 1, 2, 3};
  grid.types = {5, 14, 10};
  grid.fields = {{"c", Centering::Cell, {7.f, 8.f, 9.f}}};
  const Mesh mesh = buildMesh(std::move(grid), "test");
  EXPECT_EQ(mesh.skippedCells, 1u);
  EXPECT_EQ(mesh.tetCount(), 1u);
  EXPECT_EQ(mesh.pyramidCount(), 1u);
  // Cells are numbered tets first.
  EXPECT_EQ(mesh.fields[0].values[0], 9.f);
  EXPECT_EQ(mesh.fields[0].values[1], 8.f);
}

TEST(BuildMesh, RejectsBadIndicesAndTypes) {
  UnstructuredGrid grid;
  grid.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  grid.offsets = {0, 4};
  grid.connectivity = {0, 1, 2, 9};
  grid.types = {10};
  EXPECT_THROW(buildMesh(UnstructuredGrid(grid), "bad.vtu"), Error);
  grid.connectivity = {0, 1, 2, 3};
  grid.types = {42};
  EXPECT_THROW(buildMesh(UnstructuredGrid(grid), "bad.vtu"), Error);
}
