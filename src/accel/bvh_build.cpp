#include "accel/bvh.h"

#include "core/parallel_bounds.h"
#include "core/progress.h"
#include "mesh/cell.h"
#include <uvr/error.h>

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <string>
#include <utility>

namespace uvr {

namespace {

// Embree builds into nodes we allocate in its thread-local arenas; we flatten them afterwards.
struct BuildNode {
  bool leaf;
};

struct InnerNode : BuildNode {
  BuildNode *children[2];
  Box3f childBounds[2];
  uint32_t nodeCount, cellCount; // of the subtree, counted before flattening
};

struct LeafNode : BuildNode {
  uint32_t count;
  uint32_t cellIds[1]; // `count` entries follow
};

void *createInner(RTCThreadLocalAllocator alloc, unsigned int, void *) {
  auto *node = static_cast<InnerNode *>(rtcThreadLocalAlloc(alloc, sizeof(InnerNode), 16));
  node->leaf = false;
  node->children[0] = node->children[1] = nullptr;
  return node;
}

void setChildren(void *nodePtr, void **children, unsigned int count, void *) {
  auto *node = static_cast<InnerNode *>(nodePtr);
  for (unsigned int i = 0; i < count && i < 2; ++i)
    node->children[i] = static_cast<BuildNode *>(children[i]);
}

void setBounds(void *nodePtr, const RTCBounds **bounds, unsigned int count, void *) {
  auto *node = static_cast<InnerNode *>(nodePtr);
  for (unsigned int i = 0; i < count && i < 2; ++i)
    node->childBounds[i] = {{bounds[i]->lower_x, bounds[i]->lower_y, bounds[i]->lower_z},
                            {bounds[i]->upper_x, bounds[i]->upper_y, bounds[i]->upper_z}};
}

void *createLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive *prims, size_t count, void *) {
  auto *node = static_cast<LeafNode *>(
      rtcThreadLocalAlloc(alloc, sizeof(LeafNode) + (count - 1) * sizeof(uint32_t), 16));
  node->leaf = true;
  node->count = uint32_t(count);
  for (size_t i = 0; i < count; ++i)
    node->cellIds[i] = prims[i].primID;
  return node;
}

bool reportProgress(void *userPtr, double fraction) {
  static_cast<Progress *>(userPtr)->set(uint64_t(fraction * 1000.0));
  return true;
}

// Subtrees this close to the root are counted and flattened in parallel.
constexpr int kParallelDepth = 12;

uint32_t subtreeNodes(const BuildNode *node) {
  return node->leaf ? 1 : static_cast<const InnerNode *>(node)->nodeCount;
}

uint32_t subtreeCells(const BuildNode *node) {
  return node->leaf ? static_cast<const LeafNode *>(node)->count
                    : static_cast<const InnerNode *>(node)->cellCount;
}

/// Stores in each inner node the number of nodes and cells below it, which place subtrees in the flat arrays.
void countSubtrees(BuildNode *node, int depth) {
  if (node->leaf)
    return;
  auto *inner = static_cast<InnerNode *>(node);
  if (depth < kParallelDepth)
    tbb::parallel_invoke([&] { countSubtrees(inner->children[0], depth + 1); },
                         [&] { countSubtrees(inner->children[1], depth + 1); });
  else
    for (BuildNode *child : inner->children)
      countSubtrees(child, depth + 1);
  inner->nodeCount = 1 + subtreeNodes(inner->children[0]) + subtreeNodes(inner->children[1]);
  inner->cellCount = subtreeCells(inner->children[0]) + subtreeCells(inner->children[1]);
}

/// Writes `node` at bvh.nodes[index], its descendants from `firstFree` and its cells' ids from `firstCell`,
/// as a depth-first walk appending nodes and ids would: an inner node's children side by side, then the
/// first child's descendants, then the second's.
void flatten(const BuildNode *node, const Box3f &bounds, uint32_t index, uint32_t firstFree,
             uint32_t firstCell, int depth, Bvh &bvh) {
  if (node->leaf) {
    const auto *leaf = static_cast<const LeafNode *>(node);
    bvh.nodes[index] = {bounds, firstCell, leaf->count};
    std::copy_n(leaf->cellIds, leaf->count, bvh.cellIds.begin() + firstCell);
    return;
  }
  const auto *inner = static_cast<const InnerNode *>(node);
  bvh.nodes[index] = {bounds, firstFree, 0};
  const BuildNode *const *children = inner->children;
  auto flattenChild = [&](int i) {
    const uint32_t before = i == 0 ? 0 : subtreeNodes(children[0]) - 1;
    flatten(children[i], inner->childBounds[i], firstFree + uint32_t(i), firstFree + 2 + before,
            firstCell + (i == 0 ? 0 : subtreeCells(children[0])), depth + 1, bvh);
  };
  if (depth < kParallelDepth)
    tbb::parallel_invoke([&] { flattenChild(0); }, [&] { flattenChild(1); });
  else
    for (int i = 0; i < 2; ++i)
      flattenChild(i);
}

} // namespace

Bvh buildBvh(const MeshView &mesh) {
  const uint64_t cellCount = mesh.cellCount();
  if (cellCount == 0)
    throw Error("the mesh has no volume cells");
  if (cellCount > UINT32_MAX)
    throw Error("more than 2^32 cells are not supported by the point-location hierarchy");

  // Embree may use the array beyond the primitive count as scratch space.
  std::vector<RTCBuildPrimitive> prims(cellCount);
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, cellCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      for (uint64_t c = range.begin(); c < range.end(); ++c) {
                        const Box3f box = cellBounds(mesh, c);
                        prims[c] = {box.lower.x, box.lower.y, box.lower.z, 0,
                                    box.upper.x, box.upper.y, box.upper.z, uint32_t(c)};
                      }
                    });
  const Box3f meshBounds = parallelBounds(cellCount, [&](uint64_t c) {
    return Box3f{{prims[c].lower_x, prims[c].lower_y, prims[c].lower_z},
                 {prims[c].upper_x, prims[c].upper_y, prims[c].upper_z}};
  });

  RTCDevice device = rtcNewDevice(nullptr);
  if (!device)
    throw Error("cannot create an Embree device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) +
                ")");
  RTCBVH handle = rtcNewBVH(device);
  Progress progress("building point-location hierarchy", 1000);

  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.byteSize = sizeof(args);
  args.buildFlags = RTC_BUILD_FLAG_NONE;
  args.buildQuality =
      RTC_BUILD_QUALITY_LOW; // Morton build: several times faster; good enough to seed the walk
  args.maxBranchingFactor = 2;
  args.maxDepth = 64;
  args.sahBlockSize = 1;
  args.minLeafSize = 1;
  args.maxLeafSize = 4;
  args.traversalCost = 1.0f;
  args.intersectionCost = 2.0f; // a cell test costs more than a box test
  args.bvh = handle;
  args.primitives = prims.data();
  args.primitiveCount = prims.size();
  args.primitiveArrayCapacity = prims.size();
  args.createNode = createInner;
  args.setNodeChildren = setChildren;
  args.setNodeBounds = setBounds;
  args.createLeaf = createLeaf;
  args.buildProgress = reportProgress;
  args.userPtr = &progress;

  auto *root = static_cast<BuildNode *>(rtcBuildBVH(&args));
  if (!root) {
    const int code = int(rtcGetDeviceError(device));
    rtcReleaseBVH(handle);
    rtcReleaseDevice(device);
    throw Error("building the point-location hierarchy failed (Embree error " + std::to_string(code) + ")");
  }

  countSubtrees(root, 0);
  Bvh bvh;
  bvh.nodes.resize(subtreeNodes(root));
  bvh.cellIds.resize(subtreeCells(root));
  flatten(root, meshBounds, 0, 1, 0, 0, bvh);
  progress.finish();
  rtcReleaseBVH(handle);
  rtcReleaseDevice(device);
  return bvh;
}

} // namespace uvr
