#include "accel/seed_grid.h"
#include "mesh/cell.h"
#include "mesh/mesh.h"
#include "mesh/mesh_view.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_neighbors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

using namespace uvr;

// Each voxel's seed is, by brute force over all cells, the lowest-numbered cell holding the voxel's centre,
// or none where no cell does.
TEST(SeedGrid, SeedsEachVoxelWithTheLowestCellHoldingItsCentre) {
  for (CellType type : {CellType::Tetra, CellType::Hexahedron, CellType::Wedge, CellType::Pyramid}) {
    // Jittered, and cut along a diagonal: the staircase leaves some voxel centres in no cell.
    Mesh mesh =
        buildMesh(makeBoxGrid(
                      type, 5, {{-1.f, -1.f, -1.f}, {1.f, 2.f, 1.f}}, [](Vec3f p) { return p.x; }, 0.3f),
                  "box");
    for (auto [cells, corners] :
         {std::pair{&mesh.tets, 4}, {&mesh.pyramids, 5}, {&mesh.wedges, 6}, {&mesh.hexes, 8}}) {
      UninitVector<uint32_t> kept;
      for (size_t c = 0; c < cells->size(); c += size_t(corners)) {
        float sum = 0.f;
        for (int i = 0; i < corners; ++i)
          sum += mesh.points[(*cells)[c + size_t(i)]].x + mesh.points[(*cells)[c + size_t(i)]].y;
        if (sum / float(corners) < 0.8f)
          kept.insert(kept.end(), cells->begin() + long(c), cells->begin() + long(c) + corners);
      }
      *cells = std::move(kept);
    }
    const MeshView view = makeMeshView(mesh, -1);
    const SeedGrid seeds = buildSeedGrid(view, nullptr, 3.f);
    const VoxelGrid &grid = seeds.grid;
    ASSERT_EQ(seeds.seeds.size(), grid.voxelCount());
    ASSERT_GT(grid.voxelCount(), view.cellCount());
    uint64_t seeded = 0, empty = 0;
    for (int z = 0; z < grid.nz; ++z)
      for (int y = 0; y < grid.ny; ++y)
        for (int x = 0; x < grid.nx; ++x) {
          const Vec3f centre{grid.origin.x + (float(x) + 0.5f) * grid.voxelSize.x,
                             grid.origin.y + (float(y) + 0.5f) * grid.voxelSize.y,
                             grid.origin.z + (float(z) + 0.5f) * grid.voxelSize.z};
          uint32_t expected = kNoCell;
          for (uint64_t c = 0; c < view.cellCount() && expected == kNoCell; ++c)
            if (cellContains(view, c, centre))
              expected = uint32_t(c);
          const uint64_t voxel =
              (uint64_t(z) * uint64_t(grid.ny) + uint64_t(y)) * uint64_t(grid.nx) + uint64_t(x);
          ASSERT_EQ(seeds.seeds[voxel], expected) << "voxel " << x << " " << y << " " << z;
          EXPECT_EQ(seeds.view().seedAt(centre), expected);
          (expected == kNoCell ? empty : seeded) += 1;
        }
    EXPECT_GT(seeded, 0u);
    EXPECT_GT(empty, 0u) << "the cut should leave some centres outside";
  }
}

// The separating-axis test against a dense sampling of each triangle: true wherever a sample lies in the box
// (conservative), and only where one lies within a sample spacing of it (tight: a test of the box's axes
// alone would pass triangles that only their bounding box brings near).
TEST(SeedGrid, TriangleMeetsBoxExactly) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> corner(-2.f, 2.f);
  const Vec3f centre{0.1f, -0.2f, 0.3f}, half{0.5f, 0.7f, 0.4f};
  constexpr int kSteps = 60;
  int met = 0, missedByBoxes = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec3f a{corner(random), corner(random), corner(random)},
        b{corner(random), corner(random), corner(random)}, c{corner(random), corner(random), corner(random)};
    const float spacing = std::max({length(b - a), length(c - a), length(c - b)}) / kSteps;
    bool sampleInside = false, sampleNear = false;
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; i + j <= kSteps; ++j) {
        const Vec3f q = a + (b - a) * (float(i) / kSteps) + (c - a) * (float(j) / kSteps) - centre;
        const Vec3f excess{std::fabs(q.x) - half.x, std::fabs(q.y) - half.y, std::fabs(q.z) - half.z};
        sampleInside |= excess.x <= 0.f && excess.y <= 0.f && excess.z <= 0.f;
        sampleNear |= excess.x <= spacing && excess.y <= spacing && excess.z <= spacing;
      }
    const bool meets = triangleMeetsBox(a, b, c, centre, half);
    if (sampleInside)
      ASSERT_TRUE(meets) << k;
    if (meets)
      ASSERT_TRUE(sampleNear) << k;
    Box3f box;
    box.extend(a);
    box.extend(b);
    box.extend(c);
    const bool boxesMeet = !intersection(box, Box3f{centre - half, centre + half}).empty();
    met += meets;
    missedByBoxes += boxesMeet && !meets;
  }
  EXPECT_GT(met, 300);
  EXPECT_GT(missedByBoxes, 100) << "the triangles' boxes alone decide too many";
}

// The boundary faces' parity never calls a point in a cell outside, and calls most points outside the cells
// so.
TEST(SeedGrid, BoundaryFacesTellPointsOutsideTheMesh) {
  // A jittered lattice of tets cut along a diagonal and with a hollow middle: a boundary with concave parts.
  Mesh mesh = buildMesh(
      makeBoxGrid(
          CellType::Tetra, 12, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}}, [](Vec3f p) { return p.x; }, 0.3f),
      "box");
  UninitVector<uint32_t> kept;
  for (size_t c = 0; c < mesh.tets.size(); c += 4) {
    Vec3f centroid{0.f, 0.f, 0.f};
    for (int i = 0; i < 4; ++i)
      centroid = centroid + mesh.points[mesh.tets[c + size_t(i)]] * 0.25f;
    if (centroid.x + centroid.y < 1.f && dot(centroid, centroid) > 0.2f)
      kept.insert(kept.end(), mesh.tets.begin() + long(c), mesh.tets.begin() + long(c) + 4);
  }
  mesh.tets = std::move(kept);
  const MeshView view = makeMeshView(mesh, -1);
  const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
  for (float voxelsPerCell : {0.1f, 0.5f, 2.f}) {
    const SeedGrid grid = buildSeedGrid(view, neighbors.data(), voxelsPerCell);
    ASSERT_EQ(grid.boundaryStart.size(), grid.grid.voxelCount() + 1);
    ASSERT_FALSE(grid.boundaryFaces.empty());
    const SeedGridView seeds = grid.view();
    std::mt19937 random(11);
    std::uniform_real_distribution<float> uniform(-1.f, 1.f);
    int outside = 0, told = 0;
    for (int k = 0; k < 6000; ++k) {
      const Vec3f p{uniform(random), uniform(random), uniform(random)};
      bool inCell = false;
      for (uint64_t c = 0; c < view.cellCount() && !inCell; ++c)
        inCell = cellContains(view, c, p);
      const bool saysOutside = seeds.outsideMesh(view, p);
      ASSERT_FALSE(inCell && saysOutside) << p.x << " " << p.y << " " << p.z;
      outside += !inCell;
      told += saysOutside;
    }
    EXPECT_GT(outside, 600);
    EXPECT_GT(told, outside * 9 / 10) << voxelsPerCell << " voxels per cell";
  }
}

// Meshes with other cells than tets list no faces: their hexahedra's faces need not be flat.
TEST(SeedGrid, ListsNoFacesBesideOtherCells) {
  const Mesh mesh = buildMesh(
      makeBoxGrid(CellType::Hexahedron, 4, {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}}, [](Vec3f p) { return p.x; }),
      "box");
  const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
  const SeedGrid grid = buildSeedGrid(makeMeshView(mesh, -1), neighbors.data());
  EXPECT_TRUE(grid.boundaryStart.empty());
  EXPECT_FALSE(grid.view().outsideMesh(makeMeshView(mesh, -1), Vec3f{0.5f, 0.5f, 0.5f}));
}
