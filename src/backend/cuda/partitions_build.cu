// The GPU's twin of accel/partitions_build.cpp: the median-split KD-tree, built one level at a time, and the
// partitions' boxes, value ranges and cell counts.
#include "backend/cuda/device_builder.cuh"

#include "mesh/cell.h"

#include <cub/device/device_scan.cuh>

#include <iterator>
#include <utility>

namespace uvr::gpu_build {
namespace {

constexpr uint32_t kSettled = 0xffffffffu; // a position whose cells have reached their leaf

// ---- Partitions: the median-split KD-tree, one level at a time
//
// The cells are kept in three lists, each sorted by centroid along one axis (ties by cell index). A node's
// cells occupy the same positions in all three; its median along an axis is the middle of that axis's list,
// moved to the nearer end of the centroids of its value (the host's splitAtValue), and splitting it is a
// stable partition of each list by the side its cells fall on.

struct LevelNode {
  uint32_t start, count; ///< positions in the sorted lists
  Box3f space;           ///< the node's cell of space
  uint32_t below = 0;    ///< cells that go below the split, once classified

  __device__ bool goesAbove(uint64_t position) const { return position - start >= below; }
};

/// The node of a level (`count` nodes whose ranges of positions are disjoint and in order, as each level is
/// made) that holds position `p`, or kSettled where none does: its cells reached their leaf before. Searched
/// rather than kept per position (4 bytes a cell).
__device__ inline uint32_t nodeAt(const LevelNode *level, uint32_t count, uint64_t p) {
  uint32_t lo = 0, hi = count; // the first node that starts past p is in [lo, hi]
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (level[mid].start <= p)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == 0)
    return kSettled;
  const LevelNode node = level[lo - 1];
  return p - node.start < node.count ? lo - 1 : kSettled;
}

/// Whether `p` lies in `box`, taken half-open as the split assigns centroids (the host's holdsCentroid).
__device__ bool holdsCentroid(const Box3f &box, Vec3f p) {
  return box.lower.x <= p.x && p.x < box.upper.x && box.lower.y <= p.y && p.y < box.upper.y &&
         box.lower.z <= p.z && p.z < box.upper.z;
}

/// A piece's tree holds the cells whose centroids lie in its root: the others are sorted past them all.
constexpr uint32_t kOutsideKey = 0xffffffffu; // no finite centroid's ordered bits

/// The key cells are sorted by along `axis`: their centroids' ordered bits, those outside a piece's tree
/// last.
__device__ inline uint32_t axisKey(const MeshView &mesh, uint64_t c, int axis, bool piece,
                                   const Box3f &treeRoot) {
  const Vec3f centroid = cellCentroid(mesh, c);
  return piece && !holdsCentroid(treeRoot, centroid) ? kOutsideKey : orderedBits(centroid[axis]);
}

__global__ void axisKeysKernel(MeshView mesh, uint64_t cells, int axis, bool piece, Box3f treeRoot,
                               uint32_t *keys) {
  const uint64_t c = globalIndex();
  if (c < cells)
    keys[c] = axisKey(mesh, c, axis, piece, treeRoot);
}

/// Byte `digit` of the axis key of the cell at each position of `order`.
__global__ void axisDigitsKernel(MeshView mesh, uint64_t cells, int axis, bool piece, Box3f treeRoot,
                                 const uint32_t *order, int digit, uint8_t *digits) {
  const uint64_t p = globalIndex();
  if (p < cells)
    digits[p] = uint8_t(axisKey(mesh, order[p], axis, piece, treeRoot) >> (8 * digit));
}

__global__ void insideKernel(MeshView mesh, uint64_t cells, Box3f treeRoot, uint32_t *inside) {
  const uint64_t c = globalIndex();
  if (c < cells)
    inside[c] = holdsCentroid(treeRoot, cellCentroid(mesh, c)) ? 1u : 0u;
}

/// The first position in [first, last) of the sorted `list` whose centroid along `axis` is not below `value`
/// (`orEqual`: above it).
__device__ uint32_t boundIn(const uint32_t *list, const MeshView &mesh, int axis, uint32_t first,
                            uint32_t last, float value, bool orEqual) {
  while (first < last) {
    const uint32_t middle = first + (last - first) / 2;
    const float v = cellCentroid(mesh, list[middle])[axis];
    if (v < value || (orEqual && v == value))
      first = middle + 1;
    else
      last = middle;
  }
  return first;
}

struct SortedLists {
  const uint32_t *axis[3];
};

/// Decides per node of the level whether and where it splits, as the host's TreeBuilder::split.
__global__ void classifyKernel(LevelNode *level, uint32_t count, SortedLists lists, MeshView mesh,
                               uint32_t leafSize, int depth, KdNode *decisions, uint32_t *splits) {
  const uint64_t i = globalIndex();
  if (i >= count)
    return;
  const LevelNode node = level[i];
  KdNode decision;
  bool split = false;
  if (node.count > leafSize && depth < kMaxPartitionDepth) {
    Vec3f extent;
    for (int a = 0; a < 3; ++a)
      extent[a] = cellCentroid(mesh, lists.axis[a][node.start + node.count - 1])[a] -
                  cellCentroid(mesh, lists.axis[a][node.start])[a];
    const int axis = widestAxis(extent);
    const uint32_t *list = lists.axis[axis];
    const uint32_t end = node.start + node.count, middle = node.start + node.count / 2;
    const float median = cellCentroid(mesh, list[middle])[axis];
    const uint32_t low = boundIn(list, mesh, axis, node.start, middle, median, false),
                   high = boundIn(list, mesh, axis, middle, end, median, true);
    const uint32_t at = high == end || (low != node.start && middle - low <= high - middle) ? low : high;
    if (at > node.start && at < end) {
      decision = {cellCentroid(mesh, list[at])[axis], uint32_t(axis), 0};
      split = decision.split > node.space.lower[axis] && decision.split < node.space.upper[axis];
      level[i].below = at - node.start;
    }
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
    next[2 * rank] = {node.start, node.below, below};
    next[2 * rank + 1] = {node.start + node.below, node.count - node.below, above};
  } else {
    const uint32_t leaf = leavesBefore + uint32_t(i) - splitRank[i];
    nodes[levelBase + i] = {0.f, KdNode::kLeaf, leaf};
    leafSpace[leaf] = node.space;
  }
}

/// Which side of its node's split each cell goes to: the upper half of the split axis's list goes above.
__global__ void sideKernel(uint64_t cells, const LevelNode *level, uint32_t count, const KdNode *decisions,
                           const uint32_t *splits, SortedLists lists, uint8_t *above) {
  const uint64_t p = globalIndex();
  if (p >= cells)
    return;
  const uint32_t s = nodeAt(level, count, p);
  if (s == kSettled || !splits[s])
    return;
  above[lists.axis[decisions[s].axis][p]] = level[s].goesAbove(p);
}

/// Per node of a level, the cells that go above its split (none where it does not split); scanned, the
/// cells going above in the nodes before it.
__global__ void aboveCountsKernel(const LevelNode *level, uint32_t count, const uint32_t *splits,
                                  uint32_t *counts) {
  const uint64_t s = globalIndex();
  if (s < count)
    counts[s] = splits[s] ? level[s].count - level[s].below : 0u;
}

/// What a partition gathers from the cells whose boxes touch it, as ordered bits.
struct LeafAccumulator {
  AtomicBox cells;
  uint32_t valueMin, valueMax;
  unsigned long long count;
  unsigned long long sizeLog2Sum; ///< of cellSizeLog2, two's complement
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
  const int32_t sizeLog2 = cellSizeLog2(box);
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
    // At most 32 values of 16 bits: the 32-bit sum cannot overflow.
    const long long sizeLog2Here = int32_t(__reduce_add_sync(sharing, uint32_t(sizeLog2)));
    if ((threadIdx.x & 31u) != uint32_t(__ffs(sharing) - 1))
      return;
#else
    const uint32_t *lowerHere = lower, *upperHere = upper;
    const uint32_t valueMinHere = valueMin, valueMaxHere = valueMax;
    const unsigned long long cellsHere = 1;
    const long long sizeLog2Here = sizeLog2;
#endif
    LeafAccumulator &acc = leaves[leaf];
    acc.cells.extendBits(lowerHere, upperHere);
    atomicMin(&acc.valueMin, valueMinHere);
    atomicMax(&acc.valueMax, valueMaxHere);
    atomicAdd(&acc.count, cellsHere);
    atomicAdd(&acc.sizeLog2Sum, (unsigned long long)sizeLog2Here);
  });
}

/// Each partition's box shrunk to its cells within its cell of space, padded as the host pads it.
__global__ void finishLeavesKernel(uint32_t leafCount, const LeafAccumulator *leaves, const Box3f *leafSpace,
                                   float pad, Box3f *shrunk, float *valueMin, float *valueMax,
                                   uint64_t *counts, int64_t *sizeLog2Sums) {
  const uint64_t i = globalIndex();
  if (i >= leafCount)
    return;
  const LeafAccumulator acc = leaves[i];
  shrunk[i] = padded(intersection(acc.cells.box(), leafSpace[i]), pad);
  valueMin[i] = fromOrderedBits(acc.valueMin);
  valueMax[i] = fromOrderedBits(acc.valueMax);
  counts[i] = acc.count;
  sizeLog2Sums[i] = int64_t(acc.sizeLog2Sum);
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

} // namespace

// Outside the anonymous namespace: the scan instantiates only some of the iterators' members.

/// The stable partition of one list (below before above within each splitting node, order kept on each
/// side), one position at a time as the scan of the sides' flags reaches it: `aboveBefore`, the cells going
/// above before position p in the list, is consumed where the scan writes it, so the counts take no buffer.
struct ListPartition {
  const LevelNode *level;
  uint32_t count;
  const uint32_t *splits, *list, *aboveInNodesBefore;
  const uint8_t *above;
  uint32_t *out;

  /// The flag scanned at position p: whether its cell goes above.
  __device__ uint32_t flag(uint64_t p) const {
    const uint32_t s = nodeAt(level, count, p);
    return s != kSettled && splits[s] ? above[list[p]] : 0u;
  }
  __device__ void place(uint64_t p, uint32_t aboveBefore) const {
    const uint32_t s = nodeAt(level, count, p), cell = list[p];
    if (s == kSettled || !splits[s]) {
      out[p] = cell;
      return;
    }
    const LevelNode node = level[s];
    const uint32_t ones = aboveBefore - aboveInNodesBefore[s];
    out[above[cell] ? node.start + node.below + ones : uint32_t(p) - ones] = cell;
  }
};

/// A random-access iterator over a list's positions whose element at p is `at(p)`: a value computed where
/// read, or a slot that acts where written.
template <class At, class Value> struct PositionIterator {
  using iterator_category = std::random_access_iterator_tag;
  using value_type = Value;
  using difference_type = int64_t;
  using pointer = void;
  using reference = decltype(std::declval<const At &>()(int64_t()));
  At at;
  int64_t position = 0;

  __device__ reference operator*() const { return at(position); }
  __device__ reference operator[](int64_t i) const { return at(position + i); }
  __host__ __device__ PositionIterator operator+(int64_t i) const { return {at, position + i}; }
  __host__ __device__ PositionIterator &operator+=(int64_t i) {
    position += i;
    return *this;
  }
  __host__ __device__ PositionIterator &operator++() {
    ++position;
    return *this;
  }
  __host__ __device__ int64_t operator-(const PositionIterator &other) const {
    return position - other.position;
  }
};

/// The scan's input: each position's flag.
struct FlagAt {
  ListPartition partition;
  __device__ uint32_t operator()(int64_t p) const { return partition.flag(uint64_t(p)); }
};

/// The scan's output: writing position p's count places its cell (ListPartition::place).
struct PlaceAt {
  struct Slot {
    ListPartition partition;
    int64_t p;
    __device__ const Slot &operator=(uint32_t aboveBefore) const {
      partition.place(uint64_t(p), aboveBefore);
      return *this;
    }
  };
  ListPartition partition;
  __device__ Slot operator()(int64_t p) const { return {partition, p}; }
};

void DeviceBuilder::partitions() {
  // A piece's tree starts from its region's box, as the whole mesh's tree reaches it, over the cells whose
  // centroids lie there (as the host builds it).
  const bool piece = !mesh_.pieceRegion.empty();
  const float pad = partitionPadding(piece ? mesh_.pieceWholeBounds : meshBounds_);
  const Box3f root = padded(meshBounds_, pad);
  const Box3f treeRoot = piece ? intersection(mesh_.pieceRegion, padded(mesh_.pieceWholeBounds, pad)) : root;
  out_.partitions.rootBounds = root;

  // The three sorted lists; a spare list that each partitioned list is written to, swapped with it; the
  // sides of the cells.
  DeviceBuffer<uint32_t> lists[3], spare;
  DeviceBuffer<uint8_t> above;
  if (lean_) {
    // A byte of the key at a time, recomputed each pass: 10 bytes a cell rather than sortCells' 16, where
    // the lean layout's build would peak.
    for (int axis = 0; axis < 3; ++axis)
      sortCellsByDigits(
          [&](const uint32_t *order, int digit, uint8_t *digits) {
            axisDigitsKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, axis, piece, treeRoot, order, digit,
                                                       digits);
          },
          lists[axis]);
  } else {
    DeviceBuffer<uint32_t> keys;
    keys.resize(cells_);
    for (int axis = 0; axis < 3; ++axis) {
      axisKeysKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, axis, piece, treeRoot, keys.data());
      UVR_CUDA_CHECK(cudaGetLastError());
      sortCells(keys, 32, lists[axis]);
    }
  }
  spare.resize(cells_);
  above.resize(cells_);
  // The cells outside a piece's tree, last in every list, lie in no node: they take no part.
  uint64_t inTree = cells_;
  if (piece && cells_ > 0) {
    insideKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, treeRoot, spare.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    scratch_.run([&](void *storage, size_t &bytes) {
      return cub::DeviceScan::InclusiveSum(storage, bytes, spare.data(), spare.data(), int64_t(cells_));
    });
    inTree = downloadOne(spare.data() + cells_ - 1);
  }

  DeviceBuffer<LevelNode> level, next;
  const LevelNode rootNode{0, uint32_t(inTree), treeRoot};
  level.upload(&rootNode, 1);
  DeviceBuffer<KdNode> nodes, decisions;
  DeviceBuffer<Box3f> leafSpace;
  DeviceBuffer<uint32_t> splits, splitRank, aboveInNodesBefore;
  std::vector<std::pair<uint32_t, uint32_t>> levels; // first node and count per level
  uint32_t levelBase = 0, leaves = 0, count = 1;
  for (int depth = 0; count > 0; ++depth) {
    const SortedLists sorted{{lists[0].data(), lists[1].data(), lists[2].data()}};
    decisions.grow(count, 0);
    splits.grow(count, 0);
    splitRank.grow(count, 0);
    classifyKernel<<<blocksFor(count, kBlock), kBlock>>>(level.data(), count, sorted, mesh_, leafSize_, depth,
                                                         decisions.data(), splits.data());
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
      sideKernel<<<cellBlocks(), kBlock>>>(cells_, level.data(), count, decisions.data(), splits.data(),
                                           sorted, above.data());
      UVR_CUDA_CHECK(cudaGetLastError());
      aboveInNodesBefore.grow(count, 0);
      aboveCountsKernel<<<blocksFor(count, kBlock), kBlock>>>(level.data(), count, splits.data(),
                                                              aboveInNodesBefore.data());
      UVR_CUDA_CHECK(cudaGetLastError());
      scratch_.run([&](void *storage, size_t &bytes) {
        return cub::DeviceScan::ExclusiveSum(storage, bytes, aboveInNodesBefore.data(),
                                             aboveInNodesBefore.data(), int64_t(count));
      });
      for (int axis = 0; axis < 3; ++axis) {
        const ListPartition partition{
            level.data(), count,       splits.data(), lists[axis].data(), aboveInNodesBefore.data(),
            above.data(), spare.data()};
        scratch_.run([&](void *storage, size_t &bytes) {
          return cub::DeviceScan::ExclusiveSum(storage, bytes,
                                               PositionIterator<FlagAt, uint32_t>{{partition}},
                                               PositionIterator<PlaceAt, void>{{partition}}, int64_t(cells_));
        });
        lists[axis].swap(spare);
      }
    }
    level.swap(next);
    count = 2 * splitting;
  }
  for (auto &list : lists)
    list.release();
  spare.release();
  above.release();

  const uint32_t nodeCount = levelBase;
  out_.partitions.nodes.resize(nodeCount);
  UVR_CUDA_CHECK(cudaMemcpy(out_.partitions.nodes.data(), nodes.data(), nodeCount * sizeof(KdNode),
                            cudaMemcpyDeviceToDevice));
  DeviceBuffer<LeafAccumulator> accumulators;
  accumulators.resize(leaves);
  LeafAccumulator empty{AtomicBox::empty(), orderedBits(INFINITY), orderedBits(-INFINITY), 0, 0};
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
  DeviceBuffer<int64_t> sizeLog2Sums;
  sizeLog2Sums.resize(leaves);
  finishLeavesKernel<<<blocksFor(leaves, kBlock), kBlock>>>(
      leaves, accumulators.data(), leafSpace.data(), pad, shrunk.data(), out_.partitions.valueMin.data(),
      out_.partitions.valueMax.data(), out_.partitions.cellCounts.data(), sizeLog2Sums.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  {
    // A few numbers per partition: the host computes the scales as it does for its own build.
    std::vector<int64_t> sums(leaves);
    std::vector<uint64_t> counts(leaves);
    std::vector<KdNode> hostNodes(nodeCount);
    sizeLog2Sums.download(sums.data(), leaves);
    out_.partitions.cellCounts.download(counts.data(), leaves);
    out_.partitions.nodes.download(hostNodes.data(), nodeCount);
    const StepScales scales = computeStepScales(sums, counts, hostNodes, mesh_.stepScaleReference);
    out_.partitions.stepScale.upload(scales.partition.data(), scales.partition.size());
    out_.partitions.nodeMaxStepScale.upload(scales.node.data(), scales.node.size());
    out_.partitions.finestStepScale = scales.finest;
  }
  out_.partitions.nodeBounds.resize(nodeCount);
  for (auto it = levels.rbegin(); it != levels.rend(); ++it) {
    nodeBoundsKernel<<<blocksFor(it->second, kBlock), kBlock>>>(it->first, it->second,
                                                                out_.partitions.nodes.data(), shrunk.data(),
                                                                out_.partitions.nodeBounds.data());
    UVR_CUDA_CHECK(cudaGetLastError());
  }
}

} // namespace uvr::gpu_build
