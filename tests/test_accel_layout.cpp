// The host-side builds that run in parallel produce what their serial definitions say, on a mesh large
// enough to take the parallel paths: tet neighbours as the smallest other tet holding a face's points, and
// the BVH and partition tree in the depth-first layout of a serial build.
#include "accel/bvh.h"
#include "accel/partitions.h"
#include "mesh/mesh_view.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_neighbors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <optional>

using namespace uvr;

namespace {

/// 28^3 lattice cubes of 6 tets: 131712 cells, past the sizes below which the builds stay serial.
const Mesh &largeTetMesh() {
  static const Mesh mesh = buildMesh(makeBoxGrid(
                                         CellType::Tetra, 28, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}},
                                         [](Vec3f p) { return p.x + p.y * p.z; }, 0.3f),
                                     "lattice");
  return mesh;
}

/// Walks a tree of binary nodes as a serial depth-first build appends them (children side by side, then the
/// first child's subtree, then the second's) and checks each inner node's first child against that order.
/// `children(node)` gives an inner node's first child, or nothing for a leaf, which `leaf(node)` then sees.
void expectDepthFirstLayout(size_t nodeCount,
                            const std::function<std::optional<uint32_t>(uint32_t)> &children,
                            const std::function<void(uint32_t)> &leaf) {
  uint32_t next = 1;
  std::function<void(uint32_t)> visit = [&](uint32_t node) {
    const std::optional<uint32_t> first = children(node);
    if (!first) {
      leaf(node);
      return;
    }
    ASSERT_EQ(*first, next) << "node " << node;
    next += 2;
    visit(*first);
    visit(*first + 1);
  };
  visit(0);
  EXPECT_EQ(next, nodeCount);
}

} // namespace

TEST(AccelLayout, TetNeighborsAreTheSmallestOtherTetHoldingEachFace) {
  const Mesh &mesh = largeTetMesh();
  auto points = [&](uint32_t tet, int face) { // of the face opposite corner `face`, sorted
    std::array<uint32_t, 3> key;
    for (int i = 0; i < 3; ++i)
      key[size_t(i)] = mesh.tets[4 * size_t(tet) + size_t((face + 1 + i) % 4)];
    std::sort(key.begin(), key.end());
    return key;
  };
  std::map<std::array<uint32_t, 3>, std::vector<uint32_t>> tetsByFace;
  for (uint32_t t = 0; t < mesh.tetCount(); ++t)
    for (int face = 0; face < 4; ++face)
      tetsByFace[points(t, face)].push_back(t);
  const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
  ASSERT_EQ(neighbors.size(), 4 * mesh.tetCount());
  size_t interior = 0;
  for (uint32_t t = 0; t < mesh.tetCount(); ++t)
    for (int face = 0; face < 4; ++face) {
      uint32_t expected = 0xffffffffu;
      for (uint32_t other : tetsByFace[points(t, face)])
        if (other != t)
          expected = std::min(expected, other);
      ASSERT_EQ(neighbors[4 * size_t(t) + size_t(face)], expected) << "tet " << t << " face " << face;
      interior += expected != 0xffffffffu;
    }
  EXPECT_GT(interior, 3 * neighbors.size() / 4);
  // The boundary faces are the others, listed once each in increasing order.
  const std::vector<uint32_t> boundary = listBoundaryFaces(neighbors);
  EXPECT_EQ(boundary.size(), neighbors.size() - interior);
  for (size_t i = 0; i < boundary.size(); ++i) {
    ASSERT_EQ(neighbors[boundary[i]], 0xffffffffu) << "face " << boundary[i];
    if (i > 0)
      ASSERT_LT(boundary[i - 1], boundary[i]);
  }
}

TEST(AccelLayout, BvhIsLaidOutDepthFirstWithEachCellOnce) {
  const MeshView view = makeMeshView(largeTetMesh(), 0);
  const Bvh bvh = buildBvh(view);
  uint32_t nextCell = 0;
  expectDepthFirstLayout(
      bvh.nodes.size(),
      [&](uint32_t node) -> std::optional<uint32_t> {
        if (bvh.nodes[node].count > 0)
          return std::nullopt;
        return bvh.nodes[node].first;
      },
      [&](uint32_t node) {
        EXPECT_EQ(bvh.nodes[node].first, nextCell) << "leaf " << node;
        nextCell += bvh.nodes[node].count;
      });
  EXPECT_EQ(nextCell, view.cellCount());
  std::vector<uint32_t> cells = bvh.cellIds;
  std::sort(cells.begin(), cells.end());
  for (uint32_t c = 0; c < cells.size(); ++c)
    ASSERT_EQ(cells[c], c);
}

TEST(AccelLayout, PartitionTreeIsLaidOutDepthFirstWithLeavesInOrder) {
  const MeshView view = makeMeshView(largeTetMesh(), 0);
  const Partitions parts = buildPartitions(view, 16);
  uint32_t nextLeaf = 0;
  expectDepthFirstLayout(
      parts.nodes.size(),
      [&](uint32_t node) -> std::optional<uint32_t> {
        if (parts.nodes[node].axis == KdNode::kLeaf)
          return std::nullopt;
        return parts.nodes[node].child;
      },
      [&](uint32_t node) { EXPECT_EQ(parts.nodes[node].child, nextLeaf++) << "leaf node " << node; });
  EXPECT_EQ(nextLeaf, parts.count());
  EXPECT_GT(parts.count(), view.cellCount() / 32);
  uint64_t listed = 0;
  for (uint64_t count : parts.cellCounts)
    listed += count;
  EXPECT_GE(listed, view.cellCount());
}
