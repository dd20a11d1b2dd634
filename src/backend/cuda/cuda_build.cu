#include "backend/cuda/cuda_build.cuh"

#include "accel/occupancy_build.h"
#include "core/morton.h"
#include "core/progress.h"
#include "core/timer.h"
#include "mesh/cell.h"
#include "mesh/tet_neighbors.h"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <cstring>

namespace uvr {
namespace {

constexpr int kBlock = 256;
constexpr uint32_t kSettled = 0xffffffffu; // a position whose cells have reached their leaf

/// Floats as unsigned integers of the same order, for integer atomics and radix sorts.
UVR_HOST_DEVICE inline uint32_t orderedBits(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

UVR_HOST_DEVICE inline float fromOrderedBits(uint32_t u) {
  u = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
  float f;
  memcpy(&f, &u, sizeof f);
  return f;
}

/// A box reduced by integer atomics on ordered bits; starts empty.
struct AtomicBox {
  uint32_t lower[3], upper[3];

  static AtomicBox empty() {
    const uint32_t inf = orderedBits(INFINITY), negInf = orderedBits(-INFINITY);
    return {{inf, inf, inf}, {negInf, negInf, negInf}};
  }
  __device__ void extend(const Box3f &box) {
    const uint32_t lo[3] = {orderedBits(box.lower.x), orderedBits(box.lower.y), orderedBits(box.lower.z)},
                   hi[3] = {orderedBits(box.upper.x), orderedBits(box.upper.y), orderedBits(box.upper.z)};
    extendBits(lo, hi);
  }
  /// The same for a box given as ordered bits.
  __device__ void extendBits(const uint32_t lo[3], const uint32_t hi[3]) {
    for (int k = 0; k < 3; ++k) {
      atomicMin(&lower[k], lo[k]);
      atomicMax(&upper[k], hi[k]);
    }
  }
  UVR_HOST_DEVICE Box3f box() const {
    return {{fromOrderedBits(lower[0]), fromOrderedBits(lower[1]), fromOrderedBits(lower[2])},
            {fromOrderedBits(upper[0]), fromOrderedBits(upper[1]), fromOrderedBits(upper[2])}};
  }
};

__device__ inline uint64_t globalIndex() { return uint64_t(blockIdx.x) * blockDim.x + threadIdx.x; }

__global__ void indicesKernel(uint64_t count, uint32_t *indices) {
  const uint64_t i = globalIndex();
  if (i < count)
    indices[i] = uint32_t(i);
}

template <typename T> T downloadOne(const T *device) {
  T value;
  UVR_CUDA_CHECK(cudaMemcpy(&value, device, sizeof(T), cudaMemcpyDeviceToHost));
  return value;
}

// ---- Cell boxes

/// The centroid of every cell (partitionCentroid) and, reduced warp by warp into `bounds`, the mesh's box.
__global__ void centroidsKernel(MeshView mesh, uint64_t cells, Vec3f *centroids, AtomicBox *bounds) {
  Box3f local;
  for (uint64_t c = globalIndex(); c < cells; c += uint64_t(gridDim.x) * blockDim.x) {
    const Box3f box = cellBounds(mesh, c);
    centroids[c] = partitionCentroid(box);
    local.extend(box);
  }
  float lo[3] = {local.lower.x, local.lower.y, local.lower.z},
        hi[3] = {local.upper.x, local.upper.y, local.upper.z};
  for (int offset = 16; offset > 0; offset /= 2)
    for (int k = 0; k < 3; ++k) {
      lo[k] = fminf(lo[k], __shfl_xor_sync(0xffffffffu, lo[k], offset));
      hi[k] = fmaxf(hi[k], __shfl_xor_sync(0xffffffffu, hi[k], offset));
    }
  if (threadIdx.x % 32 == 0)
    bounds->extend({{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}});
}

// ---- Tet adjacency

__global__ void countIncidentKernel(const uint32_t *tets, uint64_t entries, unsigned long long *counts) {
  const uint64_t i = globalIndex();
  if (i < entries)
    atomicAdd(counts + tets[i], 1ull);
}

__global__ void fillIncidentKernel(const uint32_t *tets, uint64_t entries, unsigned long long *next,
                                   uint32_t *incident) {
  const uint64_t i = globalIndex();
  if (i < entries)
    incident[atomicAdd(next + tets[i], 1ull)] = uint32_t(i / 4);
}

__global__ void tetNeighborsKernel(const uint32_t *tets, uint64_t tetCount, const uint64_t *first,
                                   const uint32_t *incident, uint32_t *neighbors) {
  const uint64_t t = globalIndex();
  if (t >= tetCount)
    return;
  uint32_t across[4];
  findTetNeighbors(tets, t, first, incident, across);
  for (int i = 0; i < 4; ++i)
    neighbors[4 * t + i] = across[i];
}

// ---- Occupancy grid

__global__ void occupancyKernel(MeshView mesh, uint64_t cells, VoxelGrid grid, unsigned long long *bits) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  markCell(mesh, c, grid, [&](uint64_t w, uint64_t mask) {
    if ((bits[w] & mask) != mask)
      atomicOr(bits + w, (unsigned long long)mask);
  });
}

// ---- Seed grid

__global__ void seedKernel(MeshView mesh, uint64_t cells, VoxelGrid grid, uint32_t *seeds) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  forEachSeededVoxel(mesh, c, grid, [&](uint64_t voxel) { atomicMin(seeds + voxel, uint32_t(c)); });
}

/// Each tet face with no neighbour (a boundary face), 4 * tet + i, counted in `count` and, with `faces`
/// given, put at the slot the count reached (the order is arbitrary).
__global__ void listBoundaryFacesKernel(const uint32_t *tetNeighbors, uint64_t entries,
                                        unsigned long long *count, uint32_t *faces) {
  const uint64_t entry = globalIndex();
  if (entry >= entries || tetNeighbors[entry] != kNoCell)
    return;
  const unsigned long long slot = atomicAdd(count, 1ull);
  if (faces)
    faces[slot] = uint32_t(entry);
}

/// Per boundary face of the tets, per voxel it meets: counts the face there (`faces` null), or puts it and
/// the octants it meets in the voxel's next free slot (`slots`, advanced; the row's order is arbitrary).
__global__ void boundaryFacesKernel(MeshView mesh, const uint32_t *tetNeighbors, VoxelGrid grid,
                                    uint32_t *slots, uint32_t *faces, uint8_t *octants) {
  const uint64_t entry = globalIndex();
  if (entry >= 4 * mesh.tetCount || tetNeighbors[entry] != kNoCell)
    return;
  forEachBoundaryVoxel(mesh, uint32_t(entry), grid, [&](uint64_t voxel, uint32_t faceOctants) {
    const uint32_t slot = atomicAdd(slots + voxel, 1u);
    if (faces) {
      faces[slot] = uint32_t(entry);
      octants[slot] = uint8_t(faceOctants);
    }
  });
}

// ---- Point-location BVH

__global__ void mortonKernel(const Vec3f *centroids, uint64_t cells, Vec3f origin, Vec3f scale,
                             uint32_t *codes) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  const Vec3f p = centroids[c] - origin;
  auto cell = [](float v) { return uint32_t(fminf(fmaxf(v, 0.f), 1023.f)); };
  codes[c] = uint32_t(mortonCode(cell(p.x * scale.x), cell(p.y * scale.y), cell(p.z * scale.z)));
}

// A radix tree over the cells in Morton order (Karras 2012, "Maximizing parallelism in the construction of
// BVHs, octrees, and k-d trees"): internal node i covers a range of cells and splits it where the highest bit
// in which their codes differ changes, found by binary searches, every node at once. Subtrees of at most
// kLeafCells cells become one leaf, as the host's hierarchy is collapsed for the GPU. Children sit side by
// side as findCell expects: the root at 0, the children of the k-th kept inner node at 1 + 2k and 2 + 2k.

constexpr uint32_t kLeafCells = 8;

/// The length of the prefix that cells i and j share in their keys (Morton code, then position, so that
/// keys are distinct), or -1 where j is out of range.
__device__ inline int sharedPrefix(const uint32_t *codes, int64_t cells, int64_t i, int64_t j) {
  if (j < 0 || j >= cells)
    return -1;
  const uint32_t a = codes[i], b = codes[j];
  return a != b ? __clz(a ^ b) : 32 + __clz(uint32_t(i ^ j));
}

struct RadixNode {
  uint32_t first, last; ///< the cells it covers, positions in Morton order
  uint32_t split;       ///< its children cover [first, split] and [split + 1, last]
};

__device__ inline bool keptInner(uint32_t first, uint32_t last) { return last - first + 1 > kLeafCells; }

/// Internal node i's range and split; `kept` says whether it stays an inner node after collapsing.
__global__ void radixTreeKernel(const uint32_t *codes, int64_t cells, RadixNode *radix, uint32_t *kept) {
  const int64_t i = int64_t(globalIndex());
  if (i >= cells - 1)
    return;
  const int d = sharedPrefix(codes, cells, i, i + 1) > sharedPrefix(codes, cells, i, i - 1) ? 1 : -1;
  const int lowest = sharedPrefix(codes, cells, i, i - d);
  int64_t span = 2;
  while (sharedPrefix(codes, cells, i, i + span * d) > lowest)
    span *= 2;
  int64_t length = 0;
  for (int64_t t = span / 2; t >= 1; t /= 2)
    if (sharedPrefix(codes, cells, i, i + (length + t) * d) > lowest)
      length += t;
  const int64_t j = i + length * d;
  const int node = sharedPrefix(codes, cells, i, j);
  int64_t split = 0, step = length; // halved, rounding up, down to 1
  do {
    step = (step + 1) / 2;
    if (sharedPrefix(codes, cells, i, i + (split + step) * d) > node)
      split += step;
  } while (step > 1);
  const int64_t gamma = i + split * d + (d < 0 ? -1 : 0);
  const uint32_t first = uint32_t(i < j ? i : j), last = uint32_t(i < j ? j : i);
  radix[i] = {first, last, uint32_t(gamma)};
  kept[i] = keptInner(first, last);
}

/// Per kept inner node, its children's records (boxes aside) and, for kept children, where they are stored.
__global__ void collapsedTreeKernel(int64_t cells, const RadixNode *radix, const uint32_t *kept,
                                    const uint32_t *keptRank, BvhNode *nodes, uint32_t *parentSlot) {
  const int64_t i = int64_t(globalIndex());
  if (i >= cells - 1 || !kept[i])
    return;
  const RadixNode node = radix[i];
  const uint32_t ranges[2][2] = {{node.first, node.split}, {node.split + 1, node.last}};
  for (int side = 0; side < 2; ++side) {
    const uint32_t slot = 1 + 2 * keptRank[i] + uint32_t(side), first = ranges[side][0],
                   last = ranges[side][1];
    if (keptInner(first, last)) {
      const uint32_t child = keptRank[side == 0 ? node.split : node.split + 1];
      nodes[slot] = {Box3f{}, 1 + 2 * child, 0};
      parentSlot[child] = slot;
    } else {
      nodes[slot] = {Box3f{}, first, last - first + 1};
    }
  }
}

/// Boxes written by other threads of the running kernel: read from L2, where their writes are.
__device__ inline Box3f freshBounds(const BvhNode &node) {
  const float *f = &node.bounds.lower.x;
  return {{__ldcg(f), __ldcg(f + 1), __ldcg(f + 2)}, {__ldcg(f + 3), __ldcg(f + 4), __ldcg(f + 5)}};
}

/// The boxes, from the leaves up: the second of a node's two children to arrive computes its box.
__global__ void collapsedBoundsKernel(MeshView mesh, const uint32_t *cellIds, int64_t cells,
                                      const uint32_t *kept, const uint32_t *keptRank, BvhNode *nodes,
                                      const uint32_t *parentSlot, uint32_t *arrivals) {
  const int64_t i = int64_t(globalIndex());
  if (i >= cells - 1 || !kept[i])
    return;
  const uint32_t self = keptRank[i];
  uint32_t leaves = 0;
  for (uint32_t slot = 1 + 2 * self; slot <= 2 + 2 * self; ++slot) {
    const BvhNode child = nodes[slot]; // written by the previous kernel
    if (child.count == 0)
      continue;
    Box3f bounds;
    for (uint32_t k = child.first; k < child.first + child.count; ++k)
      bounds.extend(cellBounds(mesh, cellIds[k]));
    nodes[slot].bounds = bounds;
    ++leaves;
  }
  if (leaves == 0)
    return;
  __threadfence();
  if (atomicAdd(arrivals + self, leaves) + leaves < 2)
    return; // an inner child is not done: its thread carries on
  for (uint32_t at = self;;) {
    Box3f box = freshBounds(nodes[1 + 2 * at]);
    box.extend(freshBounds(nodes[2 + 2 * at]));
    const uint32_t slot = at == 0 ? 0u : parentSlot[at];
    nodes[slot].bounds = box;
    if (slot == 0)
      return;
    at = (slot - 1) / 2; // the kept node whose pair holds the slot
    __threadfence();
    if (atomicAdd(arrivals + at, 1u) == 0)
      return;
  }
}

// ---- Partitions: the median-split KD-tree, one level at a time
//
// The cells are kept in three lists, each sorted by centroid along one axis (ties by cell index). A node's
// cells occupy the same positions in all three; its median along an axis is the middle of that axis's list,
// and splitting it is a stable partition of each list by the side its cells fall on, as in the host's
// nth_element with the same order.

struct LevelNode {
  uint32_t start, count; ///< positions in the sorted lists
  Box3f space;           ///< the node's cell of space

  __device__ uint32_t half() const { return count / 2; } ///< cells that go below the split
  __device__ bool goesAbove(uint64_t position) const { return position - start >= half(); }
};

__global__ void axisKeysKernel(const Vec3f *centroids, uint64_t cells, int axis, uint32_t *keys) {
  const uint64_t c = globalIndex();
  if (c < cells)
    keys[c] = orderedBits(centroids[c][axis]);
}

struct SortedLists {
  const uint32_t *axis[3];
};

/// Decides per node of the level whether and where it splits, as the host's TreeBuilder::split.
__global__ void classifyKernel(const LevelNode *level, uint32_t count, SortedLists lists,
                               const Vec3f *centroids, uint32_t leafSize, int depth, KdNode *decisions,
                               uint32_t *splits) {
  const uint64_t i = globalIndex();
  if (i >= count)
    return;
  const LevelNode node = level[i];
  KdNode decision;
  bool split = false;
  if (node.count > leafSize && depth < kMaxPartitionDepth) {
    Vec3f extent;
    for (int a = 0; a < 3; ++a)
      extent[a] =
          centroids[lists.axis[a][node.start + node.count - 1]][a] - centroids[lists.axis[a][node.start]][a];
    const int axis = widestAxis(extent);
    decision = {centroids[lists.axis[axis][node.start + node.count / 2]][axis], uint32_t(axis), 0};
    split = decision.split > node.space.lower[axis] && decision.split < node.space.upper[axis];
  }
  decisions[i] = decision;
  splits[i] = split;
}

/// Writes the level's nodes: inner ones with their children (the next level, in order), leaves with their
/// partition index and cell of space.
__global__ void emitKernel(const LevelNode *level, uint32_t count, const KdNode *decisions,
                           const uint32_t *splits, const uint32_t *splitRank, uint32_t levelBase,
                           uint32_t leavesBefore, KdNode *nodes, LevelNode *next, Box3f *leafSpace) {
  const uint64_t i = globalIndex();
  if (i >= count)
    return;
  const LevelNode node = level[i];
  if (splits[i]) {
    const uint32_t rank = splitRank[i];
    KdNode inner = decisions[i];
    inner.child = levelBase + count + 2 * rank;
    nodes[levelBase + i] = inner;
    Box3f below = node.space, above = node.space;
    below.upper[int(inner.axis)] = inner.split;
    above.lower[int(inner.axis)] = inner.split;
    next[2 * rank] = {node.start, node.half(), below};
    next[2 * rank + 1] = {node.start + node.half(), node.count - node.half(), above};
  } else {
    const uint32_t leaf = leavesBefore + uint32_t(i) - splitRank[i];
    nodes[levelBase + i] = {0.f, KdNode::kLeaf, leaf};
    leafSpace[leaf] = node.space;
  }
}

/// Which side of its node's split each cell goes to: the upper half of the split axis's list goes above.
__global__ void sideKernel(uint64_t cells, const uint32_t *positionNode, const LevelNode *level,
                           const KdNode *decisions, const uint32_t *splits, SortedLists lists,
                           uint8_t *above) {
  const uint64_t p = globalIndex();
  if (p >= cells)
    return;
  const uint32_t s = positionNode[p];
  if (s == kSettled || !splits[s])
    return;
  above[lists.axis[decisions[s].axis][p]] = level[s].goesAbove(p);
}

__global__ void aboveFlagsKernel(uint64_t cells, const uint32_t *positionNode, const uint32_t *splits,
                                 const uint32_t *list, const uint8_t *above, uint32_t *flags) {
  const uint64_t p = globalIndex();
  if (p >= cells)
    return;
  const uint32_t s = positionNode[p];
  flags[p] = s != kSettled && splits[s] ? above[list[p]] : 0u;
}

/// The stable partition of one list: below before above within each splitting node, order kept on each side.
__global__ void partitionListKernel(uint64_t cells, const uint32_t *positionNode, const LevelNode *level,
                                    const uint32_t *splits, const uint32_t *list, const uint8_t *above,
                                    const uint32_t *aboveBefore, uint32_t *out) {
  const uint64_t p = globalIndex();
  if (p >= cells)
    return;
  const uint32_t s = positionNode[p], cell = list[p];
  if (s == kSettled || !splits[s]) {
    out[p] = cell;
    return;
  }
  const LevelNode node = level[s];
  const uint32_t ones = aboveBefore[p] - aboveBefore[node.start];
  out[above[cell] ? node.start + node.half() + ones : uint32_t(p) - ones] = cell;
}

__global__ void advancePositionsKernel(uint64_t cells, uint32_t *positionNode, const LevelNode *level,
                                       const uint32_t *splits, const uint32_t *splitRank) {
  const uint64_t p = globalIndex();
  if (p >= cells)
    return;
  const uint32_t s = positionNode[p];
  if (s == kSettled)
    return;
  if (!splits[s]) {
    positionNode[p] = kSettled;
    return;
  }
  positionNode[p] = 2 * splitRank[s] + (level[s].goesAbove(p) ? 1u : 0u);
}

/// What a partition gathers from the cells whose boxes touch it, as ordered bits.
struct LeafAccumulator {
  AtomicBox cells;
  uint32_t valueMin, valueMax;
  unsigned long long count;
};

__global__ void clearLeavesKernel(uint32_t leafCount, LeafAccumulator empty, LeafAccumulator *leaves) {
  const uint64_t i = globalIndex();
  if (i < leafCount)
    leaves[i] = empty;
}

__global__ void gatherLeavesKernel(MeshView mesh, uint64_t cells, const KdNode *nodes,
                                   LeafAccumulator *leaves) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  const Box3f box = cellBounds(mesh, c);
  float lo, hi;
  cellValueRange(mesh, c, lo, hi);
  const uint32_t lower[3] = {orderedBits(box.lower.x), orderedBits(box.lower.y), orderedBits(box.lower.z)},
                 upper[3] = {orderedBits(box.upper.x), orderedBits(box.upper.y), orderedBits(box.upper.z)};
  const uint32_t valueMin = orderedBits(lo), valueMax = orderedBits(hi);
  forEachLeafTouching(nodes, box, [&](uint32_t leaf) {
#if __CUDA_ARCH__ >= 800
    // Neighbouring cells mostly lie in the same leaf, and every cell's atomics on one leaf's addresses made
    // large leaves slow to gather: the lanes of the warp that share the leaf combine their values first, and
    // the lowest of them updates it.
    const uint32_t sharing = __match_any_sync(__activemask(), leaf);
    uint32_t lowerHere[3], upperHere[3];
    for (int k = 0; k < 3; ++k) {
      lowerHere[k] = __reduce_min_sync(sharing, lower[k]);
      upperHere[k] = __reduce_max_sync(sharing, upper[k]);
    }
    const uint32_t valueMinHere = __reduce_min_sync(sharing, valueMin),
                   valueMaxHere = __reduce_max_sync(sharing, valueMax);
    const unsigned long long cellsHere = __popc(sharing);
    if ((threadIdx.x & 31u) != uint32_t(__ffs(sharing) - 1))
      return;
#else
    const uint32_t *lowerHere = lower, *upperHere = upper;
    const uint32_t valueMinHere = valueMin, valueMaxHere = valueMax;
    const unsigned long long cellsHere = 1;
#endif
    LeafAccumulator &acc = leaves[leaf];
    acc.cells.extendBits(lowerHere, upperHere);
    atomicMin(&acc.valueMin, valueMinHere);
    atomicMax(&acc.valueMax, valueMaxHere);
    atomicAdd(&acc.count, cellsHere);
  });
}

/// Each partition's box shrunk to its cells within its cell of space, padded as the host pads it.
__global__ void finishLeavesKernel(uint32_t leafCount, const LeafAccumulator *leaves, const Box3f *leafSpace,
                                   float pad, Box3f *shrunk, float *valueMin, float *valueMax,
                                   uint64_t *counts) {
  const uint64_t i = globalIndex();
  if (i >= leafCount)
    return;
  const LeafAccumulator acc = leaves[i];
  shrunk[i] = padded(intersection(acc.cells.box(), leafSpace[i]), pad);
  valueMin[i] = fromOrderedBits(acc.valueMin);
  valueMax[i] = fromOrderedBits(acc.valueMax);
  counts[i] = acc.count;
}

/// Node boxes of one level, from the level below (children come after their parents).
__global__ void nodeBoundsKernel(uint32_t first, uint32_t count, const KdNode *nodes, const Box3f *shrunk,
                                 Box3f *nodeBounds) {
  const uint64_t i = globalIndex();
  if (i >= count)
    return;
  const uint32_t node = first + uint32_t(i);
  const KdNode n = nodes[node];
  if (n.axis == KdNode::kLeaf) {
    nodeBounds[node] = shrunk[n.child];
  } else {
    Box3f box = nodeBounds[n.child];
    box.extend(nodeBounds[n.child + 1]);
    nodeBounds[node] = box;
  }
}

class DeviceBuilder {
public:
  DeviceBuilder(const MeshView &mesh, uint64_t pointCount, uint32_t leafSize, DeviceAcceleration &out)
      : mesh_(mesh), cells_(mesh.cellCount()), pointCount_(pointCount), leafSize_(leafSize), out_(out) {}

  const std::vector<std::pair<std::string, double>> &stepMs() const { return stepMs_; }

  void build() {
    if (cells_ == 0)
      throw Error("the mesh has no volume cells");
    if (cells_ >= UINT32_MAX)
      throw Error("more than 2^32 - 1 cells are not supported by the GPU build");
    if (leafSize_ == 0)
      throw Error("the partition leaf size must be at least 1");
    Progress progress("building acceleration on the GPU", 7);
    step("cell centroids", &DeviceBuilder::centroids, progress);
    step("tet adjacency", &DeviceBuilder::tetAdjacency, progress);
    step("occupancy grid", &DeviceBuilder::occupancy, progress);
    step("seed grid", &DeviceBuilder::seeds, progress);
    step("boundary faces", &DeviceBuilder::boundaryFaceList, progress);
    step("point-location hierarchy", &DeviceBuilder::bvh, progress);
    step("partitions", &DeviceBuilder::partitions, progress);
    progress.finish();
  }

private:
  void step(const char *name, void (DeviceBuilder::*work)(), Progress &progress) {
    const Timer timer;
    (this->*work)();
    UVR_CUDA_CHECK(cudaGetLastError());
    UVR_CUDA_CHECK(cudaDeviceSynchronize()); // a fault in the step surfaces here
    stepMs_.emplace_back(name, timer.milliseconds());
    progress.advance(1);
  }

  unsigned cellBlocks() const { return blocksFor(cells_, kBlock); }

  void centroids() {
    centroids_.resize(cells_);
    DeviceBuffer<AtomicBox> bounds;
    const AtomicBox empty = AtomicBox::empty();
    bounds.upload(&empty, 1);
    const unsigned blocks = std::min(cellBlocks(), 4096u); // each thread reduces several cells first
    centroidsKernel<<<blocks, kBlock>>>(mesh_, cells_, centroids_.data(), bounds.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    meshBounds_ = downloadOne(bounds.data()).box();
  }

  void tetAdjacency() {
    const uint64_t tets = mesh_.tetCount, entries = 4 * tets;
    if (tets == 0)
      return;
    DeviceBuffer<uint64_t> counts, first;
    counts.resize(pointCount_);
    first.resize(pointCount_ + 1);
    UVR_CUDA_CHECK(cudaMemset(counts.data(), 0, counts.bytes()));
    UVR_CUDA_CHECK(cudaMemset(first.data(), 0, sizeof(uint64_t)));
    auto *counters = reinterpret_cast<unsigned long long *>(counts.data());
    countIncidentKernel<<<blocksFor(entries, kBlock), kBlock>>>(mesh_.tets, entries, counters);
    UVR_CUDA_CHECK(cudaGetLastError());
    scratch_.run([&](void *storage, size_t &bytes) {
      return cub::DeviceScan::InclusiveSum(storage, bytes, counts.data(), first.data() + 1,
                                           int64_t(pointCount_));
    });
    // Each point's next free slot in its row: the row starts, shifted by one.
    UVR_CUDA_CHECK(cudaMemcpy(counts.data(), first.data(), counts.bytes(), cudaMemcpyDeviceToDevice));
    DeviceBuffer<uint32_t> incident;
    incident.resize(entries);
    fillIncidentKernel<<<blocksFor(entries, kBlock), kBlock>>>(mesh_.tets, entries, counters,
                                                               incident.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    out_.tetNeighbors.resize(entries);
    tetNeighborsKernel<<<blocksFor(tets, kBlock), kBlock>>>(mesh_.tets, tets, first.data(), incident.data(),
                                                            out_.tetNeighbors.data());
  }

  void occupancy() {
    OccupancyBits<DeviceStorage> &grid = out_.occupancy;
    grid.grid = placeVoxelGrid(meshBounds_, cells_, kDefaultVoxelsPerCell);
    grid.bits.resize(grid.wordCount());
    UVR_CUDA_CHECK(cudaMemset(grid.bits.data(), 0, grid.bits.bytes()));
    occupancyKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, grid.grid,
                                              reinterpret_cast<unsigned long long *>(grid.bits.data()));
  }

  void seeds() {
    out_.seeds.grid = placeVoxelGrid(meshBounds_, cells_, kDefaultSeedVoxelsPerCell);
    out_.seeds.seeds.resize(out_.seeds.grid.voxelCount());
    UVR_CUDA_CHECK(cudaMemset(out_.seeds.seeds.data(), 0xff, out_.seeds.seeds.bytes())); // kNoCell
    seedKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, out_.seeds.grid, out_.seeds.seeds.data());
    if (listsBoundaryFaces(mesh_))
      boundaryFaces();
  }

  /// Every boundary face, for the per-frame crossings: counted, then listed.
  void boundaryFaceList() {
    if (!listsBoundaryFaces(mesh_))
      return;
    const uint64_t entries = 4 * mesh_.tetCount;
    DeviceBuffer<unsigned long long> count;
    count.resize(1);
    UVR_CUDA_CHECK(cudaMemset(count.data(), 0, count.bytes()));
    listBoundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(out_.tetNeighbors.data(), entries,
                                                                    count.data(), nullptr);
    UVR_CUDA_CHECK(cudaGetLastError());
    out_.boundaryFaceList.resize(downloadOne(count.data()));
    UVR_CUDA_CHECK(cudaMemset(count.data(), 0, count.bytes()));
    listBoundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(
        out_.tetNeighbors.data(), entries, count.data(), out_.boundaryFaceList.data());
    UVR_CUDA_CHECK(cudaGetLastError());
  }

  /// Compressed rows of the boundary faces per voxel, as the host lists them: counted, offset by a scan, then
  /// filled.
  void boundaryFaces() {
    const uint64_t voxels = out_.seeds.seeds.size(), entries = 4 * mesh_.tetCount;
    DeviceBuffer<uint32_t> slots;
    slots.resize(voxels + 1);
    UVR_CUDA_CHECK(cudaMemset(slots.data(), 0, slots.bytes()));
    boundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(
        mesh_, out_.tetNeighbors.data(), out_.seeds.grid, slots.data(), nullptr, nullptr);
    UVR_CUDA_CHECK(cudaGetLastError());
    // Summed in 64 bits: past 2^32 - 1 entries the rows cannot be numbered, and the grid lists none.
    DeviceBuffer<unsigned long long> total;
    total.resize(1);
    scratch_.run([&](void *storage, size_t &bytes) {
      return cub::DeviceReduce::Sum(storage, bytes, slots.data(), total.data(), int64_t(voxels));
    });
    if (downloadOne(total.data()) > UINT32_MAX)
      return;
    out_.seeds.boundaryStart.resize(voxels + 1);
    scratch_.run([&](void *storage, size_t &bytes) {
      return cub::DeviceScan::ExclusiveSum(storage, bytes, slots.data(), out_.seeds.boundaryStart.data(),
                                           int64_t(voxels + 1));
    });
    out_.seeds.boundaryFaces.resize(downloadOne(out_.seeds.boundaryStart.data() + voxels));
    out_.seeds.boundaryOctants.resize(out_.seeds.boundaryFaces.size());
    UVR_CUDA_CHECK(
        cudaMemcpy(slots.data(), out_.seeds.boundaryStart.data(), slots.bytes(), cudaMemcpyDeviceToDevice));
    boundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(
        mesh_, out_.tetNeighbors.data(), out_.seeds.grid, slots.data(), out_.seeds.boundaryFaces.data(),
        out_.seeds.boundaryOctants.data());
  }

  /// The cells' indices ordered by `keys` (their low `bits` bits; ties by index) into `order`, and the keys
  /// in that order into `sortedKeys`.
  void sortCells(const DeviceBuffer<uint32_t> &keys, int bits, DeviceBuffer<uint32_t> &sortedKeys,
                 DeviceBuffer<uint32_t> &order) {
    if (cellIndices_.size() != cells_) {
      cellIndices_.resize(cells_);
      indicesKernel<<<cellBlocks(), kBlock>>>(cells_, cellIndices_.data());
      UVR_CUDA_CHECK(cudaGetLastError());
    }
    sortedKeys.resize(cells_);
    order.resize(cells_);
    scratch_.run([&](void *storage, size_t &bytes) {
      return cub::DeviceRadixSort::SortPairs(storage, bytes, keys.data(), sortedKeys.data(),
                                             cellIndices_.data(), order.data(), int64_t(cells_), 0, bits);
    });
  }

  void bvh() {
    DeviceBuffer<uint32_t> codes, sortedCodes;
    codes.resize(cells_);
    const Vec3f extent = meshBounds_.size();
    auto scaleOf = [](float e) { return e > 0.f ? 1024.f / e : 0.f; };
    mortonKernel<<<cellBlocks(), kBlock>>>(centroids_.data(), cells_, meshBounds_.lower,
                                           {scaleOf(extent.x), scaleOf(extent.y), scaleOf(extent.z)},
                                           codes.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    sortCells(codes, 30, sortedCodes, out_.bvh.cellIds);
    if (cells_ <= kLeafCells) { // one leaf
      const BvhNode root{meshBounds_, 0, uint32_t(cells_)};
      out_.bvh.nodes.upload(&root, 1);
      return;
    }
    const int64_t inner = int64_t(cells_) - 1;
    DeviceBuffer<RadixNode> radix;
    DeviceBuffer<uint32_t> kept, keptRank;
    radix.resize(inner);
    kept.resize(inner);
    keptRank.resize(inner);
    radixTreeKernel<<<blocksFor(inner, kBlock), kBlock>>>(sortedCodes.data(), int64_t(cells_), radix.data(),
                                                          kept.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    scratch_.run([&](void *storage, size_t &bytes) {
      return cub::DeviceScan::ExclusiveSum(storage, bytes, kept.data(), keptRank.data(), inner);
    });
    const uint32_t keptCount =
        downloadOne(keptRank.data() + inner - 1) + downloadOne(kept.data() + inner - 1);
    out_.bvh.nodes.resize(1 + 2 * uint64_t(keptCount));
    const BvhNode root{Box3f{}, 1, 0}; // its box comes from below
    UVR_CUDA_CHECK(cudaMemcpy(out_.bvh.nodes.data(), &root, sizeof root, cudaMemcpyHostToDevice));
    DeviceBuffer<uint32_t> parentSlot, arrivals;
    parentSlot.resize(keptCount);
    arrivals.resize(keptCount);
    UVR_CUDA_CHECK(cudaMemset(arrivals.data(), 0, arrivals.bytes()));
    collapsedTreeKernel<<<blocksFor(inner, kBlock), kBlock>>>(int64_t(cells_), radix.data(), kept.data(),
                                                              keptRank.data(), out_.bvh.nodes.data(),
                                                              parentSlot.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    collapsedBoundsKernel<<<blocksFor(inner, kBlock), kBlock>>>(
        mesh_, out_.bvh.cellIds.data(), int64_t(cells_), kept.data(), keptRank.data(), out_.bvh.nodes.data(),
        parentSlot.data(), arrivals.data());
  }

  void partitions() {
    const float pad = partitionPadding(meshBounds_);
    const Box3f root = padded(meshBounds_, pad);
    out_.partitions.rootBounds = root;

    // The three sorted lists, and their partitioned copies.
    DeviceBuffer<uint32_t> lists[3], spare[3];
    {
      DeviceBuffer<uint32_t> keys, sortedKeys;
      keys.resize(cells_);
      for (int axis = 0; axis < 3; ++axis) {
        axisKeysKernel<<<cellBlocks(), kBlock>>>(centroids_.data(), cells_, axis, keys.data());
        UVR_CUDA_CHECK(cudaGetLastError());
        sortCells(keys, 32, sortedKeys, lists[axis]);
      }
      cellIndices_.release();
    }
    for (auto &list : spare)
      list.resize(cells_);
    DeviceBuffer<uint32_t> positionNode, flags, aboveBefore;
    DeviceBuffer<uint8_t> above;
    positionNode.resize(cells_);
    flags.resize(cells_);
    aboveBefore.resize(cells_);
    above.resize(cells_);
    UVR_CUDA_CHECK(cudaMemset(positionNode.data(), 0, positionNode.bytes()));

    DeviceBuffer<LevelNode> level, next;
    const LevelNode rootNode{0, uint32_t(cells_), root};
    level.upload(&rootNode, 1);
    DeviceBuffer<KdNode> nodes, decisions;
    DeviceBuffer<Box3f> leafSpace;
    DeviceBuffer<uint32_t> splits, splitRank;
    std::vector<std::pair<uint32_t, uint32_t>> levels; // first node and count per level
    uint32_t levelBase = 0, leaves = 0, count = 1;
    for (int depth = 0; count > 0; ++depth) {
      const SortedLists sorted{{lists[0].data(), lists[1].data(), lists[2].data()}};
      decisions.grow(count, 0);
      splits.grow(count, 0);
      splitRank.grow(count, 0);
      classifyKernel<<<blocksFor(count, kBlock), kBlock>>>(level.data(), count, sorted, centroids_.data(),
                                                           leafSize_, depth, decisions.data(), splits.data());
      UVR_CUDA_CHECK(cudaGetLastError());
      scratch_.run([&](void *storage, size_t &bytes) {
        return cub::DeviceScan::ExclusiveSum(storage, bytes, splits.data(), splitRank.data(), int64_t(count));
      });
      const uint32_t splitting =
          downloadOne(splitRank.data() + count - 1) + downloadOne(splits.data() + count - 1);
      const uint32_t newLeaves = count - splitting;
      nodes.grow(levelBase + count, levelBase);
      leafSpace.grow(leaves + newLeaves, leaves);
      next.grow(2 * uint64_t(splitting), 0);
      emitKernel<<<blocksFor(count, kBlock), kBlock>>>(level.data(), count, decisions.data(), splits.data(),
                                                       splitRank.data(), levelBase, leaves, nodes.data(),
                                                       next.data(), leafSpace.data());
      UVR_CUDA_CHECK(cudaGetLastError());
      levels.emplace_back(levelBase, count);
      levelBase += count;
      leaves += newLeaves;
      if (splitting > 0) {
        sideKernel<<<cellBlocks(), kBlock>>>(cells_, positionNode.data(), level.data(), decisions.data(),
                                             splits.data(), sorted, above.data());
        UVR_CUDA_CHECK(cudaGetLastError());
        for (int axis = 0; axis < 3; ++axis) {
          aboveFlagsKernel<<<cellBlocks(), kBlock>>>(cells_, positionNode.data(), splits.data(),
                                                     lists[axis].data(), above.data(), flags.data());
          UVR_CUDA_CHECK(cudaGetLastError());
          scratch_.run([&](void *storage, size_t &bytes) {
            return cub::DeviceScan::ExclusiveSum(storage, bytes, flags.data(), aboveBefore.data(),
                                                 int64_t(cells_));
          });
          partitionListKernel<<<cellBlocks(), kBlock>>>(cells_, positionNode.data(), level.data(),
                                                        splits.data(), lists[axis].data(), above.data(),
                                                        aboveBefore.data(), spare[axis].data());
          UVR_CUDA_CHECK(cudaGetLastError());
          lists[axis].swap(spare[axis]);
        }
        advancePositionsKernel<<<cellBlocks(), kBlock>>>(cells_, positionNode.data(), level.data(),
                                                         splits.data(), splitRank.data());
        UVR_CUDA_CHECK(cudaGetLastError());
      }
      level.swap(next);
      count = 2 * splitting;
    }
    centroids_.release();

    const uint32_t nodeCount = levelBase;
    out_.partitions.nodes.resize(nodeCount);
    UVR_CUDA_CHECK(cudaMemcpy(out_.partitions.nodes.data(), nodes.data(), nodeCount * sizeof(KdNode),
                              cudaMemcpyDeviceToDevice));
    DeviceBuffer<LeafAccumulator> accumulators;
    accumulators.resize(leaves);
    LeafAccumulator empty{AtomicBox::empty(), orderedBits(INFINITY), orderedBits(-INFINITY), 0};
    clearLeavesKernel<<<blocksFor(leaves, kBlock), kBlock>>>(leaves, empty, accumulators.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    gatherLeavesKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, out_.partitions.nodes.data(),
                                                 accumulators.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    DeviceBuffer<Box3f> &shrunk = out_.partitions.bounds;
    shrunk.resize(leaves);
    out_.partitions.valueMin.resize(leaves);
    out_.partitions.valueMax.resize(leaves);
    out_.partitions.cellCounts.resize(leaves);
    finishLeavesKernel<<<blocksFor(leaves, kBlock), kBlock>>>(
        leaves, accumulators.data(), leafSpace.data(), pad, shrunk.data(), out_.partitions.valueMin.data(),
        out_.partitions.valueMax.data(), out_.partitions.cellCounts.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    out_.partitions.nodeBounds.resize(nodeCount);
    for (auto it = levels.rbegin(); it != levels.rend(); ++it) {
      nodeBoundsKernel<<<blocksFor(it->second, kBlock), kBlock>>>(it->first, it->second,
                                                                  out_.partitions.nodes.data(), shrunk.data(),
                                                                  out_.partitions.nodeBounds.data());
      UVR_CUDA_CHECK(cudaGetLastError());
    }
  }

  MeshView mesh_;
  uint64_t cells_, pointCount_;
  uint32_t leafSize_;
  DeviceAcceleration &out_;
  std::vector<std::pair<std::string, double>> stepMs_;
  DeviceBuffer<Vec3f> centroids_;
  DeviceBuffer<uint32_t> cellIndices_; // 0, 1, 2, ...: what the sorts order
  Box3f meshBounds_;
  CubScratch scratch_;
};

} // namespace

std::vector<std::pair<std::string, double>> buildOnDevice(const MeshView &mesh, uint64_t pointCount,
                                                          uint32_t leafSize, DeviceAcceleration &out) {
  DeviceBuilder builder(mesh, pointCount, leafSize, out);
  builder.build();
  return builder.stepMs();
}

} // namespace uvr
