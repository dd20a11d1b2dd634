#include "accel/partitions.h"

#include "core/error.h"
#include "core/progress.h"
#include "mesh/cell.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace uvr {

namespace {

struct CellInfo {
  Box3f bounds;
  float valueMin, valueMax;
};

/// What a leaf gathers from the cells whose boxes touch it.
struct LeafAccumulator {
  Box3f cells;
  float valueMin = INFINITY, valueMax = -INFINITY;
  uint64_t count = 0;

  void add(const CellInfo &cell) {
    cells.extend(cell.bounds);
    valueMin = minf(valueMin, cell.valueMin);
    valueMax = maxf(valueMax, cell.valueMax);
    ++count;
  }
  void merge(const LeafAccumulator &other) {
    cells.extend(other.cells);
    valueMin = minf(valueMin, other.valueMin);
    valueMax = maxf(valueMax, other.valueMax);
    count += other.count;
  }
};

/// Splits `ids` (cells by centroid) in place at the median centroid along the axis where the centroids spread
/// most (paper §2.1), down to `leafSize` cells. Nodes are appended children-adjacent, as KdNode expects.
class TreeBuilder {
public:
  TreeBuilder(const std::vector<Vec3f> &centroids, uint32_t leafSize, Partitions &parts)
      : centroids_(centroids), leafSize_(leafSize), parts_(parts) {}

  void build(uint32_t node, const Box3f &box, uint32_t *first, uint32_t *last, int depth) {
    const size_t count = size_t(last - first);
    if (count > leafSize_ && depth < 48) {
      Box3f spread;
      for (const uint32_t *id = first; id < last; ++id)
        spread.extend(centroids_[*id]);
      const Vec3f extent = spread.size();
      const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
      uint32_t *middle = first + count / 2;
      std::nth_element(first, middle, last,
                       [&](uint32_t a, uint32_t b) { return centroids_[a][axis] < centroids_[b][axis]; });
      const float split = centroids_[*middle][axis];
      // A split on the box's face leaves one side empty: stop there.
      if (split > box.lower[axis] && split < box.upper[axis]) {
        const auto child = uint32_t(parts_.nodes.size());
        parts_.nodes[node] = {split, uint32_t(axis), child};
        parts_.nodes.resize(parts_.nodes.size() + 2);
        Box3f below = box, above = box;
        below.upper[axis] = split;
        above.lower[axis] = split;
        // Cells with centroid at the split go below or above arbitrarily: their boxes are assigned later.
        build(child, below, first, middle, depth + 1);
        build(child + 1, above, middle, last, depth + 1);
        return;
      }
    }
    parts_.nodes[node] = {0.f, KdNode::kLeaf, uint32_t(parts_.bounds.size())};
    parts_.bounds.push_back(box); // the leaf's cell of space, shrunk once its cells are known
  }

private:
  const std::vector<Vec3f> &centroids_;
  uint32_t leafSize_;
  Partitions &parts_;
};

/// Adds `cell` to every leaf its box touches (a cell straddling leaves is listed in each, paper §2.1).
void addToLeaves(const Partitions &parts, const CellInfo &cell, std::vector<LeafAccumulator> &leaves) {
  uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const KdNode &node = parts.nodes[stack[--top]];
    if (node.axis == KdNode::kLeaf) {
      leaves[node.child].add(cell);
      continue;
    }
    if (cell.bounds.lower[int(node.axis)] <= node.split && top < 64)
      stack[top++] = node.child;
    if (cell.bounds.upper[int(node.axis)] >= node.split && top < 64)
      stack[top++] = node.child + 1;
  }
}

} // namespace

Partitions buildPartitions(const MeshView &mesh, uint32_t leafSize) {
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
                        if (!mesh.values) {
                          info.valueMin = info.valueMax = 0.f; // geometry alone, e.g. to count partitions
                        } else if (mesh.cellCentered) {
                          // A NaN cell has no value to draw: an empty range, which the leaf's min/max ignore.
                          const float value = mesh.values[c];
                          info.valueMin = value == value ? value : INFINITY;
                          info.valueMax = value == value ? value : -INFINITY;
                        } else {
                          info.valueMin = INFINITY;
                          info.valueMax = -INFINITY;
                          forEachCellVertex(mesh, c, [&](uint32_t v) {
                            // fminf/fmaxf skip NaN, so one NaN vertex cannot poison the range.
                            info.valueMin = fminf(info.valueMin, mesh.values[v]);
                            info.valueMax = fmaxf(info.valueMax, mesh.values[v]);
                          });
                        }
                      }
                    });

  Box3f root;
  for (const CellInfo &info : cells)
    root.extend(info.bounds);
  // Padding keeps samples on the outermost faces inside the root, whatever the rounding of the slab test.
  const float pad = 1e-5f * length(root.size()) + 1e-30f;
  root.lower = root.lower - Vec3f{pad, pad, pad};
  root.upper = root.upper + Vec3f{pad, pad, pad};

  Partitions parts;
  parts.rootBounds = root;
  {
    std::vector<Vec3f> centroids(cellCount);
    std::vector<uint32_t> ids(cellCount);
    for (uint64_t c = 0; c < cellCount; ++c) {
      centroids[c] = cells[c].bounds.center();
      ids[c] = uint32_t(c);
    }
    parts.nodes.resize(1);
    TreeBuilder(centroids, leafSize, parts).build(0, root, ids.data(), ids.data() + cellCount, 0);
  }

  // Each thread gathers into its own accumulators, merged afterwards: no atomics on the hot path.
  const uint32_t leafCount = parts.count();
  tbb::enumerable_thread_specific<std::vector<LeafAccumulator>> perThread(
      [&] { return std::vector<LeafAccumulator>(leafCount); });
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, cellCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      std::vector<LeafAccumulator> &leaves = perThread.local();
                      for (uint64_t c = range.begin(); c < range.end(); ++c)
                        addToLeaves(parts, cells[c], leaves);
                      progress.advance(range.size());
                    });
  std::vector<LeafAccumulator> leaves(leafCount);
  for (const std::vector<LeafAccumulator> &local : perThread)
    for (uint32_t i = 0; i < leafCount; ++i)
      leaves[i].merge(local[i]);

  parts.valueMin.resize(leafCount);
  parts.valueMax.resize(leafCount);
  parts.cellCounts.resize(leafCount);
  for (uint32_t i = 0; i < leafCount; ++i) {
    // Shrunk to the cells it holds, within the leaf (paper §2.2); padded as the root is, since the leaf's own
    // t-interval clips it at render time.
    Box3f shrunk = intersection(leaves[i].cells, parts.bounds[i]);
    shrunk.lower = shrunk.lower - Vec3f{pad, pad, pad};
    shrunk.upper = shrunk.upper + Vec3f{pad, pad, pad};
    parts.bounds[i] = shrunk;
    parts.valueMin[i] = leaves[i].valueMin;
    parts.valueMax[i] = leaves[i].valueMax;
    parts.cellCounts[i] = leaves[i].count;
  }
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
