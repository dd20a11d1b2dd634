#include "accel/partitions.h"

#include "core/parallel_bounds.h"
#include "core/progress.h"
#include "mesh/cell.h"
#include <uvr/error.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <utility>

namespace uvr {

namespace {

struct CellInfo {
  Box3f bounds;
  float valueMin, valueMax;
  int32_t sizeLog2; ///< cellSizeLog2
};

/// What a leaf gathers from the cells whose boxes touch it.
struct LeafAccumulator {
  Box3f cells;
  float valueMin = INFINITY, valueMax = -INFINITY;
  uint64_t count = 0;
  int64_t sizeLog2Sum = 0;

  void add(const CellInfo &cell) {
    cells.extend(cell.bounds);
    valueMin = minf(valueMin, cell.valueMin);
    valueMax = maxf(valueMax, cell.valueMax);
    ++count;
    sizeLog2Sum += cell.sizeLog2;
  }
  void merge(const LeafAccumulator &other) {
    cells.extend(other.cells);
    valueMin = minf(valueMin, other.valueMin);
    valueMax = maxf(valueMax, other.valueMax);
    count += other.count;
    sizeLog2Sum += other.sizeLog2Sum;
  }
};

/// A cell's centroid and index, ordered along an axis by centroid and then by index.
struct Centroid {
  Vec3f p;
  uint32_t cell;
};

/// Reorders [first, last) so that `middle` holds the element that would be there if sorted along `axis`,
/// none after it smaller and none before it larger.
void selectMedian(Centroid *first, Centroid *middle, Centroid *last, int axis) {
  auto along = [&](auto axisConstant) {
    std::nth_element(first, middle, last, [](const Centroid &a, const Centroid &b) {
      constexpr int kAxis = decltype(axisConstant)::value;
      return a.p[kAxis] < b.p[kAxis] || (a.p[kAxis] == b.p[kAxis] && a.cell < b.cell);
    });
  };
  if (axis == 0)
    along(std::integral_constant<int, 0>{});
  else if (axis == 1)
    along(std::integral_constant<int, 1>{});
  else
    along(std::integral_constant<int, 2>{});
}

/// Moves `middle`, the median along `axis` after selectMedian, to the nearer end of the centroids of its
/// value, so that those go wholly above the split (or wholly below, where that is nearer the median):
/// centroids on the split go above it, as a region's box holds them (lower <= p < upper). Which side a cell
/// takes then depends on its centroid alone, not on its index, so that a piece of the mesh (other cells,
/// another order) builds the same subtree over the same centroids. Returns the split position, or NaN where
/// every centroid has the same value along `axis`.
float splitAtValue(Centroid *first, Centroid *&middle, Centroid *last, int axis) {
  const float median = middle->p[axis];
  Centroid *low = std::partition(first, middle, [&](const Centroid &c) { return c.p[axis] < median; });
  Centroid *high = std::partition(middle, last, [&](const Centroid &c) { return c.p[axis] <= median; });
  if (low == first && high == last)
    return NAN;
  if (high == last || (low != first && middle - low <= high - middle)) {
    middle = low;
    return median;
  }
  middle = high;
  return std::min_element(high, last,
                          [&](const Centroid &a, const Centroid &b) { return a.p[axis] < b.p[axis]; })
      ->p[axis];
}

/// Nodes and leaf boxes of a subtree, as the depth-first build lays them out: nodes[0] is the root, and an
/// inner node's children are appended side by side before either child's subtree.
struct Subtree {
  std::vector<KdNode> nodes;
  std::vector<Box3f> leafBounds; ///< the leaves' cells of space, in depth-first order
};

/// Splits cells at the median centroid along the axis where the centroids spread most (paper §2.1), down to
/// `leafSize` cells. Subtrees of many cells are built in parallel and joined in the layout of the serial
/// depth-first build, so that the result does not depend on the threads.
class TreeBuilder {
public:
  explicit TreeBuilder(uint32_t leafSize) : leafSize_(leafSize) {}

  Subtree build(const Box3f &box, Centroid *first, Centroid *last, int depth = 0) const {
    Subtree tree;
    tree.nodes.resize(1);
    if (size_t(last - first) < kParallelCells) {
      buildSerial(tree, 0, box, first, last, depth);
      return tree;
    }
    KdNode node;
    Centroid *middle;
    if (!split(box, first, last, depth, node, middle)) {
      setLeaf(tree, 0, box);
      return tree;
    }
    const std::array<Box3f, 2> childBox = childBoxes(box, node);
    Subtree halves[2];
    tbb::parallel_invoke([&] { halves[0] = build(childBox[0], first, middle, depth + 1); },
                         [&] { halves[1] = build(childBox[1], middle, last, depth + 1); });
    // The serial layout: this node, its two children, the lower child's descendants, then the upper's.
    node.child = 1;
    tree.nodes = {node, {}, {}};
    auto descendants = uint32_t(tree.nodes.size()), leaves = 0u;
    for (int side = 0; side < 2; ++side) {
      const Subtree &half = halves[side];
      auto placed = [&](KdNode n) {
        n.child += n.axis == KdNode::kLeaf ? leaves : descendants - 1;
        return n;
      };
      tree.nodes[1 + side] = placed(half.nodes[0]);
      for (size_t i = 1; i < half.nodes.size(); ++i)
        tree.nodes.push_back(placed(half.nodes[i]));
      tree.leafBounds.insert(tree.leafBounds.end(), half.leafBounds.begin(), half.leafBounds.end());
      descendants += uint32_t(half.nodes.size() - 1);
      leaves += uint32_t(half.leafBounds.size());
    }
    return tree;
  }

private:
  // Below this many cells a subtree is built serially: each parallel level copies the nodes below it.
  static constexpr size_t kParallelCells = 1 << 16;

  /// Picks the split of [first, last) and reorders it about the median; false where the node is a leaf.
  bool split(const Box3f &box, Centroid *first, Centroid *last, int depth, KdNode &node,
             Centroid *&middle) const {
    const size_t count = size_t(last - first);
    if (count <= leafSize_ || depth >= kMaxPartitionDepth)
      return false;
    const int axis = widestAxis(parallelBounds(count, [&](uint64_t i) { return first[i].p; }).size());
    middle = first + count / 2;
    selectMedian(first, middle, last, axis);
    node = {splitAtValue(first, middle, last, axis), uint32_t(axis), 0};
    // A split on the box's face leaves one side empty: stop there (also where no split exists: NaN).
    return node.split > box.lower[axis] && node.split < box.upper[axis];
  }

  /// Makes tree.nodes[index] the root of the subtree of [first, last), appending its descendants.
  void buildSerial(Subtree &tree, uint32_t index, const Box3f &box, Centroid *first, Centroid *last,
                   int depth) const {
    KdNode node;
    Centroid *middle;
    if (!split(box, first, last, depth, node, middle)) {
      setLeaf(tree, index, box);
      return;
    }
    node.child = uint32_t(tree.nodes.size());
    tree.nodes[index] = node;
    tree.nodes.resize(tree.nodes.size() + 2);
    const std::array<Box3f, 2> childBox = childBoxes(box, node);
    // Cells with centroid at the split go above; their boxes are assigned later.
    buildSerial(tree, node.child, childBox[0], first, middle, depth + 1);
    buildSerial(tree, node.child + 1, childBox[1], middle, last, depth + 1);
  }

  static void setLeaf(Subtree &tree, uint32_t index, const Box3f &box) {
    tree.nodes[index] = {0.f, KdNode::kLeaf, uint32_t(tree.leafBounds.size())};
    tree.leafBounds.push_back(box); // the leaf's cell of space, shrunk once its cells are known
  }

  /// The cells of space below and above the split.
  static std::array<Box3f, 2> childBoxes(const Box3f &box, const KdNode &node) {
    Box3f below = box, above = box;
    below.upper[int(node.axis)] = node.split;
    above.lower[int(node.axis)] = node.split;
    return {below, above};
  }

  uint32_t leafSize_;
};

} // namespace

StepScales computeStepScales(const std::vector<int64_t> &sizeLog2Sums,
                             const std::vector<uint64_t> &cellCounts, const std::vector<KdNode> &nodes,
                             double reference) {
  int64_t sum = 0;
  uint64_t count = 0;
  for (size_t i = 0; i < cellCounts.size(); ++i) {
    sum += sizeLog2Sums[i];
    count += cellCounts[i];
  }
  const double mean = std::isnan(reference) ? double(sum) / double(count) : reference;
  StepScales scales;
  scales.mean = mean;
  scales.partition.assign(cellCounts.size(), 1.f);
  for (size_t i = 0; i < cellCounts.size() && count > 0; ++i) {
    if (cellCounts[i] == 0)
      continue;
    // Volumes in 1/256ths of log2: a length ratio of 2 is 3 * 256 apart.
    const double ratio = (double(sizeLog2Sums[i]) / double(cellCounts[i]) - mean) / 768.0;
    scales.partition[i] = std::ldexp(1.f, int(std::clamp(std::lround(ratio), -3l, 3l)));
  }
  scales.node.assign(nodes.size(), 1.f);
  for (size_t node = nodes.size(); node-- > 0;) { // children follow their parents
    const KdNode &n = nodes[node];
    scales.node[node] = n.axis == KdNode::kLeaf ? scales.partition[n.child]
                                                : std::max(scales.node[n.child], scales.node[n.child + 1]);
  }
  for (float s : scales.partition)
    scales.finest = std::min(scales.finest, s);
  return scales;
}

void computePartitionValueRanges(const MeshView &mesh, std::span<const KdNode> nodes, uint32_t count,
                                 std::span<float> valueMin, std::span<float> valueMax) {
  if (valueMin.size() != count || valueMax.size() != count)
    throw Error("partition value ranges: wrong output size");
  struct Range {
    float lo = INFINITY, hi = -INFINITY;
  };
  tbb::enumerable_thread_specific<std::vector<Range>> perThread([&] { return std::vector<Range>(count); });
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, mesh.cellCount()),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      std::vector<Range> &leaves = perThread.local();
                      for (uint64_t c = range.begin(); c < range.end(); ++c) {
                        float lo, hi;
                        cellValueRange(mesh, c, lo, hi);
                        forEachLeafTouching(nodes.data(), cellBounds(mesh, c), [&](uint32_t leaf) {
                          leaves[leaf].lo = minf(leaves[leaf].lo, lo);
                          leaves[leaf].hi = maxf(leaves[leaf].hi, hi);
                        });
                      }
                    });
  tbb::parallel_for(uint32_t(0), count, [&](uint32_t i) {
    Range leaf;
    for (const std::vector<Range> &local : perThread) {
      leaf.lo = minf(leaf.lo, local[i].lo);
      leaf.hi = maxf(leaf.hi, local[i].hi);
    }
    valueMin[i] = leaf.lo;
    valueMax[i] = leaf.hi;
  });
}

namespace {

/// Whether `p` lies in `box`, taken half-open as the split assigns centroids: lower <= p < upper.
bool holdsCentroid(const Box3f &box, Vec3f p) {
  return box.lower.x <= p.x && p.x < box.upper.x && box.lower.y <= p.y && p.y < box.upper.y &&
         box.lower.z <= p.z && p.z < box.upper.z;
}

int splitRegion(RegionSplit &split, const Box3f &box, Centroid *first, Centroid *last, int firstRegion,
                int count) {
  const int index = int(split.nodes.size());
  split.nodes.emplace_back();
  const size_t cells = size_t(last - first);
  if (count == 1 || cells < 2) {
    split.nodes[size_t(index)].region = firstRegion;
    split.regions[size_t(firstRegion)] = box;
    return index; // more regions than cells: the others stay empty
  }
  // TreeBuilder::split's choice: the axis the centroids spread most along, the median by position, the
  // centroids on the split above it.
  const int axis = widestAxis(parallelBounds(cells, [&](uint64_t i) { return first[i].p; }).size());
  const int below = count / 2;
  Centroid *middle = first + cells * size_t(below) / size_t(count);
  selectMedian(first, middle, last, axis);
  float position = splitAtValue(first, middle, last, axis);
  if (std::isnan(position)) { // every centroid alike along the axis: the regions below hold none
    position = first->p[axis];
    middle = first;
  }
  Box3f lower = box, upper = box;
  lower.upper[axis] = position;
  upper.lower[axis] = position;
  const int belowNode = splitRegion(split, lower, first, middle, firstRegion, below);
  const int aboveNode = splitRegion(split, upper, middle, last, firstRegion + below, count - below);
  split.nodes[size_t(index)] = {axis, position, belowNode, aboveNode, -1};
  return index;
}

} // namespace

RegionSplit splitRegions(const MeshView &mesh, int count) {
  const uint64_t cellCount = mesh.cellCount();
  std::vector<Centroid> centroids(cellCount);
  tbb::parallel_for(uint64_t(0), cellCount, [&](uint64_t c) {
    centroids[c] = {partitionCentroid(cellBounds(mesh, c)), uint32_t(c)};
  });
  const Box3f meshBounds = parallelBounds(cellCount, [&](uint64_t c) { return cellBounds(mesh, c); });
  RegionSplit split;
  split.regions.assign(size_t(std::max(count, 1)), Box3f{});
  splitRegion(split, padded(meshBounds, partitionPadding(meshBounds)), centroids.data(),
              centroids.data() + cellCount, 0, std::max(count, 1));
  return split;
}

Partitions buildPartitions(const MeshView &mesh, uint32_t leafSize, std::vector<int64_t> *sizeLog2Sums) {
  const uint64_t cellCount = mesh.cellCount();
  if (cellCount == 0)
    throw Error("the mesh has no volume cells");
  if (leafSize == 0)
    throw Error("the partition leaf size must be at least 1");

  Progress progress("building partitions", cellCount);
  std::vector<CellInfo> cells(cellCount);
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, cellCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      for (uint64_t c = range.begin(); c < range.end(); ++c) {
                        CellInfo &info = cells[c];
                        info.bounds = cellBounds(mesh, c);
                        cellValueRange(mesh, c, info.valueMin, info.valueMax);
                        info.sizeLog2 = cellSizeLog2(info.bounds);
                      }
                    });

  const Box3f meshBounds = parallelBounds(cellCount, [&](uint64_t c) { return cells[c].bounds; });
  const bool piece = !mesh.pieceRegion.empty();
  const float pad = partitionPadding(piece ? mesh.pieceWholeBounds : meshBounds);
  const Box3f root = padded(meshBounds, pad);
  // A piece's tree starts from its region's box, as the whole mesh's tree reaches it; its cells may reach
  // past the region, and the root bounds hold them all.
  const Box3f treeRoot = piece ? intersection(mesh.pieceRegion, padded(mesh.pieceWholeBounds, pad)) : root;

  Partitions parts;
  parts.rootBounds = root;
  {
    std::vector<Centroid> centroids(cellCount);
    tbb::parallel_for(uint64_t(0), cellCount, [&](uint64_t c) {
      centroids[c] = {partitionCentroid(cells[c].bounds), uint32_t(c)};
    });
    // A piece's tree is the whole mesh's below its region: over the cells the whole tree puts there.
    if (piece)
      centroids.erase(std::remove_if(centroids.begin(), centroids.end(),
                                     [&](const Centroid &c) { return !holdsCentroid(treeRoot, c.p); }),
                      centroids.end());
    Subtree tree =
        TreeBuilder(leafSize).build(treeRoot, centroids.data(), centroids.data() + centroids.size());
    parts.nodes = std::move(tree.nodes);
    parts.bounds = std::move(tree.leafBounds);
  }

  // Each thread gathers into its own accumulators, merged afterwards: no atomics on the hot path.
  const uint32_t leafCount = parts.count();
  tbb::enumerable_thread_specific<std::vector<LeafAccumulator>> perThread(
      [&] { return std::vector<LeafAccumulator>(leafCount); });
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, cellCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      std::vector<LeafAccumulator> &leaves = perThread.local();
                      for (uint64_t c = range.begin(); c < range.end(); ++c)
                        forEachLeafTouching(parts.nodes.data(), cells[c].bounds,
                                            [&](uint32_t leaf) { leaves[leaf].add(cells[c]); });
                      progress.advance(range.size());
                    });
  parts.valueMin.resize(leafCount);
  parts.valueMax.resize(leafCount);
  parts.cellCounts.resize(leafCount);
  std::vector<int64_t> leafSizeLog2Sums(leafCount);
  tbb::parallel_for(uint32_t(0), leafCount, [&](uint32_t i) {
    LeafAccumulator leaf;
    for (const std::vector<LeafAccumulator> &local : perThread)
      leaf.merge(local[i]);
    // Shrunk to the cells it holds, within the leaf (paper §2.2); padded as the root is, since the leaf's own
    // t-interval clips it at render time.
    parts.bounds[i] = padded(intersection(leaf.cells, parts.bounds[i]), pad);
    parts.valueMin[i] = leaf.valueMin;
    parts.valueMax[i] = leaf.valueMax;
    parts.cellCounts[i] = leaf.count;
    leafSizeLog2Sums[i] = leaf.sizeLog2Sum;
  });
  StepScales scales =
      computeStepScales(leafSizeLog2Sums, parts.cellCounts, parts.nodes, mesh.stepScaleReference);
  parts.stepScale = std::move(scales.partition);
  parts.nodeMaxStepScale = std::move(scales.node);
  parts.finestStepScale = scales.finest;
  if (sizeLog2Sums)
    *sizeLog2Sums = std::move(leafSizeLog2Sums);
  // Children follow their parents in `nodes`, so one backward pass gathers each subtree's box.
  parts.nodeBounds.assign(parts.nodes.size(), Box3f{});
  for (size_t node = parts.nodes.size(); node-- > 0;) {
    const KdNode &n = parts.nodes[node];
    if (n.axis == KdNode::kLeaf) {
      parts.nodeBounds[node] = parts.bounds[n.child];
    } else {
      parts.nodeBounds[node] = parts.nodeBounds[n.child];
      parts.nodeBounds[node].extend(parts.nodeBounds[n.child + 1]);
    }
  }
  progress.finish();
  return parts;
}

} // namespace uvr
