// Point location through the BVH: it finds a cell holding the point wherever one does.
#include "accel/bvh.h"
#include "mesh/cell.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <random>

using namespace uvr;

TEST(Bvh, FindsACellWhereverOneHoldsThePoint) {
  const Box3f box{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, 7, box, [](Vec3f p) { return p.x; }, 0.2f),
                                "box");
    const MeshView view = makeMeshView(mesh, 0);
    const Bvh bvh = buildBvh(view);
    std::mt19937 random(7);
    std::uniform_real_distribution<float> coordinate(-1.1f, 1.1f);
    int inside = 0;
    for (int i = 0; i < 2000; ++i) {
      const Vec3f p{coordinate(random), coordinate(random), coordinate(random)};
      float value;
      bool anyHolds = false;
      for (uint64_t c = 0; c < view.cellCount() && !anyHolds; ++c)
        anyHolds = sampleCell(view, c, p, value);
      const bool found =
          findCell(bvh.view(), p, [&](uint32_t cell) { return sampleCell(view, cell, p, value); });
      ASSERT_EQ(found, anyHolds) << p.x << "," << p.y << "," << p.z;
      inside += found;
    }
    EXPECT_GT(inside, 1000);
  }
}
