// Point location through the BVH: the collapsed copy the GPU gets finds a containing cell wherever the full
// hierarchy does.
#include "accel/bvh.h"
#include "mesh/cell.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <random>

using namespace uvr;

namespace {

/// The cell `findCell` settles on for `p`, or kNone.
constexpr uint32_t kNone = 0xffffffffu;
uint32_t locate(const MeshView &mesh, const Bvh &bvh, Vec3f p) {
  uint32_t found = kNone;
  findCell(bvh.view(), p, [&](uint32_t cell) {
    float value;
    if (!sampleCell(mesh, cell, p, value))
      return false;
    found = cell;
    return true;
  });
  return found;
}

} // namespace

TEST(Bvh, CollapsedHierarchyFindsACellWhereverTheFullOneDoes) {
  const Box3f box{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 9, box, [](Vec3f p) { return p.x; }, 0.2f),
                              "box");
  const MeshView view = makeMeshView(mesh, 0);
  const Bvh full = buildBvh(view);
  for (uint32_t leafCells : {1u, 4u, 8u, 1u << 30}) {
    const Bvh collapsed = collapseBvh(full, leafCells);
    EXPECT_EQ(collapsed.cellIds, full.cellIds);
    uint32_t largestLeaf = 0;
    for (const BvhNode &node : collapsed.nodes)
      largestLeaf = std::max(largestLeaf, node.count);
    EXPECT_LE(largestLeaf, std::max(leafCells, 4u)); // the builder's own leaves hold up to 4
    if (leafCells >= 4)
      EXPECT_LT(collapsed.nodes.size(), full.nodes.size() / 2);
    std::mt19937 random(7);
    std::uniform_real_distribution<float> coordinate(-1.1f, 1.1f);
    int inside = 0;
    for (int i = 0; i < 3000; ++i) {
      const Vec3f p{coordinate(random), coordinate(random), coordinate(random)};
      const uint32_t a = locate(view, full, p), b = locate(view, collapsed, p);
      ASSERT_EQ(a == kNone, b == kNone) << p.x << "," << p.y << "," << p.z;
      float value;
      if (b != kNone)
        EXPECT_TRUE(sampleCell(view, b, p, value));
      inside += b != kNone;
    }
    EXPECT_GT(inside, 1500);
  }
}
