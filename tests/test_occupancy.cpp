#include "accel/occupancy.h"
#include "mesh/cell.h"
#include "mesh/mesh_view.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <random>

using namespace uvr;

// Every point in a cell must be kept (a cleared voxel there would drop samples); points well outside the mesh
// should mostly be rejected, or the grid is useless.
TEST(Occupancy, KeepsEveryPointInACellAndRejectsEmptySpace) {
  for (CellType type : {CellType::Tetra, CellType::Hexahedron, CellType::Wedge, CellType::Pyramid}) {
    // A ball-shaped mesh: the lattice's cells whose centroid lies inside a sphere, so the bounds hold empty
    // corners.
    UnstructuredGrid lattice = makeBoxGrid(
        type, 10, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}}, [](Vec3f p) { return p.x; }, 0.3f);
    const Mesh box = buildMesh(std::move(lattice), "lattice");
    Mesh ball = box;
    UninitVector<uint32_t> *arrays[] = {&ball.tets, &ball.pyramids, &ball.wedges, &ball.hexes};
    const int corners[] = {4, 5, 6, 8};
    for (int a = 0; a < 4; ++a) {
      UninitVector<uint32_t> kept;
      for (size_t c = 0; c < arrays[a]->size(); c += size_t(corners[a])) {
        Vec3f centroid{0.f, 0.f, 0.f};
        for (int i = 0; i < corners[a]; ++i)
          centroid = centroid + box.points[(*arrays[a])[c + size_t(i)]] * (1.f / float(corners[a]));
        if (dot(centroid, centroid) < 0.8f)
          kept.insert(kept.end(), arrays[a]->begin() + long(c), arrays[a]->begin() + long(c) + corners[a]);
      }
      *arrays[a] = kept;
    }
    ball.fields.clear();
    const MeshView view = makeMeshView(ball, -1);
    const OccupancyGrid grid = buildOccupancyGrid(view);
    const OccupancyView occupancy = grid.view();

    std::mt19937 random(7);
    std::uniform_real_distribution<float> uniform(0.f, 1.f);
    int outside = 0, rejected = 0;
    for (uint64_t c = 0; c < view.cellCount(); ++c) {
      // Random weights of its corners: inside a tet, inside the box of any other cell.
      for (int k = 0; k < 20; ++k) {
        Vec3f p{0.f, 0.f, 0.f};
        float total = 0.f;
        forEachCellVertex(view, c, [&](uint32_t v) {
          const float w = uniform(random);
          p = p + view.points[v] * w;
          total += w;
        });
        p = p * (1.f / total);
        EXPECT_TRUE(occupancy.mayHoldCell(p)) << "cell " << c;
      }
    }
    for (int k = 0; k < 2000; ++k) {
      const Vec3f p{2.f * uniform(random) - 1.f, 2.f * uniform(random) - 1.f, 2.f * uniform(random) - 1.f};
      if (dot(p, p) > 1.5f) { // beyond every kept cell
        ++outside;
        rejected += !occupancy.mayHoldCell(p);
      }
    }
    EXPECT_GT(rejected, outside * 3 / 4);
  }
}
