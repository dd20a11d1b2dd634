#include "accel/partitions.h"

#include "core/error.h"
#include "core/progress.h"
#include "mesh/cell.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <memory>

namespace uvr {

namespace {

struct CellInfo {
  Box3f bounds;
  float valueMin, valueMax;
};

struct BuildNode {
  int axis = KdNode::kLeaf;
  float split = 0.f;
  std::unique_ptr<BuildNode> below, above;
  // Leaf only.
  Box3f shrunk;
  float valueMin = INFINITY, valueMax = -INFINITY;
  uint64_t cellCount = 0;
};

class Builder {
public:
  Builder(const std::vector<CellInfo> &cells, uint32_t leafSize, Progress &progress)
      : cells_(cells), leafSize_(leafSize), progress_(progress) {}

  /// `ids` are the cells whose boxes touch `box`, the node's cell of space.
  std::unique_ptr<BuildNode> build(const Box3f &box, std::vector<uint32_t> ids, int depth) {
    auto node = std::make_unique<BuildNode>();
    int axis = -1;
    float split = 0.f;
    if (ids.size() > leafSize_ && depth < 48)
      chooseSplit(box, ids, axis, split);

    std::vector<uint32_t> below, above;
    if (axis >= 0) {
      for (uint32_t id : ids) {
        if (cells_[id].bounds.lower[axis] <= split)
          below.push_back(id);
        if (cells_[id].bounds.upper[axis] >= split)
          above.push_back(id);
      }
      // A split that sends every cell to both sides only duplicates work.
      if (below.size() == ids.size() && above.size() == ids.size())
        axis = -1;
    }
    if (axis < 0) {
      makeLeaf(*node, box, ids);
      return node;
    }

    ids = {};
    Box3f boxBelow = box, boxAbove = box;
    boxBelow.upper[axis] = split;
    boxAbove.lower[axis] = split;
    node->axis = axis;
    node->split = split;
    auto buildBelow = [&] { node->below = build(boxBelow, std::move(below), depth + 1); };
    auto buildAbove = [&] { node->above = build(boxAbove, std::move(above), depth + 1); };
    if (below.size() + above.size() > 65536)
      tbb::parallel_invoke(buildBelow, buildAbove);
    else
      buildBelow(), buildAbove();
    return node;
  }

private:
  /// Median of the cell centroids along the axis where they spread most (paper §2.1).
  void chooseSplit(const Box3f &box, const std::vector<uint32_t> &ids, int &axis, float &split) const {
    Box3f centroids;
    for (uint32_t id : ids)
      centroids.extend(cells_[id].bounds.center());
    const Vec3f extent = centroids.size();
    axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    std::vector<float> keys(ids.size());
    for (size_t i = 0; i < ids.size(); ++i)
      keys[i] = cells_[ids[i]].bounds.center()[axis];
    auto middle = keys.begin() + std::ptrdiff_t(keys.size() / 2);
    std::nth_element(keys.begin(), middle, keys.end());
    split = *middle;
    if (!(split > box.lower[axis] && split < box.upper[axis]))
      axis = -1;
  }

  void makeLeaf(BuildNode &node, const Box3f &box, const std::vector<uint32_t> &ids) {
    Box3f cellsBox;
    for (uint32_t id : ids) {
      cellsBox.extend(cells_[id].bounds);
      node.valueMin = std::min(node.valueMin, cells_[id].valueMin);
      node.valueMax = std::max(node.valueMax, cells_[id].valueMax);
    }
    node.shrunk = intersection(cellsBox, box); // paper §2.2
    node.cellCount = ids.size();
    progress_.advance(ids.size());
  }

  const std::vector<CellInfo> &cells_;
  uint32_t leafSize_;
  Progress &progress_;
};

void flatten(BuildNode &node, uint32_t index, Partitions &parts) {
  if (node.axis == int(KdNode::kLeaf)) {
    parts.nodes[index] = {0.f, KdNode::kLeaf, uint32_t(parts.bounds.size())};
    parts.bounds.push_back(node.shrunk);
    parts.valueMin.push_back(node.valueMin);
    parts.valueMax.push_back(node.valueMax);
    parts.cellCounts.push_back(node.cellCount);
    return;
  }
  const auto child = uint32_t(parts.nodes.size());
  parts.nodes[index] = {node.split, uint32_t(node.axis), child};
  parts.nodes.resize(parts.nodes.size() + 2);
  flatten(*node.below, child, parts);
  flatten(*node.above, child + 1, parts);
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
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, cellCount), [&](const tbb::blocked_range<uint64_t> &range) {
    for (uint64_t c = range.begin(); c < range.end(); ++c) {
      CellInfo &info = cells[c];
      info.bounds = cellBounds(mesh, c);
      if (!mesh.values) {
        info.valueMin = info.valueMax = 0.f; // geometry alone, e.g. to count partitions
      } else if (mesh.cellCentered) {
        info.valueMin = info.valueMax = mesh.values[c];
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

  std::vector<uint32_t> ids(cellCount);
  for (uint64_t c = 0; c < cellCount; ++c)
    ids[c] = uint32_t(c);
  Builder builder(cells, leafSize, progress);
  std::unique_ptr<BuildNode> tree = builder.build(root, std::move(ids), 0);

  Partitions parts;
  parts.rootBounds = root;
  parts.nodes.resize(1);
  flatten(*tree, 0, parts);
  // Shrunk boxes get the same padding, clipped to their leaf by the leaf's own interval at render time.
  for (Box3f &box : parts.bounds) {
    box.lower = box.lower - Vec3f{pad, pad, pad};
    box.upper = box.upper + Vec3f{pad, pad, pad};
  }
  progress.finish();
  return parts;
}

} // namespace uvr
