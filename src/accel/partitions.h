// The paper's partitions (§2.1-2.2): leaves of a median-split KD-tree, convex and disjoint, each box shrunk
// to the cells it holds, with the scalar range of those cells. Flat arrays, usable on host and device.
#pragma once

#include "core/host_device.h"
#include "core/storage.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "mesh/mesh_view.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace uvr {

/// An inner node splits at `split` on `axis` (0-2) into nodes[child] (below) and nodes[child + 1] (above);
/// a leaf (axis == kLeaf) is partition `child`.
struct KdNode {
  static constexpr uint32_t kLeaf = 3;
  static constexpr uint32_t kNone = ~0u; ///< no node: what lies past the partitions
  float split = 0.f;
  uint32_t axis = kLeaf;
  uint32_t child = 0;
};

struct PartitionsView {
  const KdNode *nodes = nullptr;
  const Box3f *nodeBounds = nullptr; ///< per node, the union of the shrunk boxes of the partitions below
  const float *valueMin = nullptr;   ///< scalar range per partition, for the transfer-function metadata
  const float *valueMax = nullptr;
  const float *stepScale = nullptr;        ///< per partition, see PartitionArrays
  const float *nodeMaxStepScale = nullptr; ///< per KD node, the largest stepScale below
  Box3f rootBounds;                        ///< the mesh bounds, slightly padded: the KD-tree's root cell
  uint32_t count = 0;
  float finestStepScale = 1.f; ///< the smallest stepScale
};

template <typename Storage> struct PartitionArrays {
  template <typename T> using Array = typename Storage::template Array<T>;
  Array<KdNode> nodes;
  Array<Box3f> nodeBounds;
  Array<Box3f> bounds;             ///< shrunk box per partition (what nodeBounds holds for its leaf)
  Array<float> valueMin, valueMax; ///< scalar range of the cells listed in each partition
  Array<uint64_t> cellCounts;      ///< cells listed (a cell straddling leaves is listed in each)
  /// Per partition, the size of its cells against the mesh's, as a power of two from 1/8 to 8 (see
  /// computeStepScales): steps that follow the mesh scale by it.
  Array<float> stepScale;
  Array<float> nodeMaxStepScale; ///< per KD node, the largest stepScale below
  Box3f rootBounds;
  float finestStepScale = 1.f;

  uint32_t count() const { return uint32_t(bounds.size()); }
  PartitionsView view() const {
    return {nodes.data(),    nodeBounds.data(), valueMin.data(),
            valueMax.data(), stepScale.data(),  nodeMaxStepScale.data(),
            rootBounds,      count(),           finestStepScale};
  }
  template <typename A, typename B, typename F> static void forEachMember(A &a, B &b, F &&f) {
    f(a.nodes, b.nodes);
    f(a.nodeBounds, b.nodeBounds);
    f(a.bounds, b.bounds);
    f(a.valueMin, b.valueMin);
    f(a.valueMax, b.valueMax);
    f(a.cellCounts, b.cellCounts);
    f(a.stepScale, b.stepScale);
    f(a.nodeMaxStepScale, b.nodeMaxStepScale);
    f(a.rootBounds, b.rootBounds);
    f(a.finestStepScale, b.finestStepScale);
  }
};
using Partitions = PartitionArrays<HostStorage>;

/// Median-split KD-tree over cell centroids until a leaf holds at most `leafSize` cells. `sizeLog2Sums`,
/// where given, takes the sum of cellSizeLog2 over each partition's cells (what its step scale comes from).
Partitions buildPartitions(const MeshView &mesh, uint32_t leafSize,
                           std::vector<int64_t> *sizeLog2Sums = nullptr);

/// The top levels of the tree buildPartitions makes of `mesh`, down to `count` regions (for a power of 2, the
/// same median splits; otherwise split in proportion to the regions on each side), for the pieces of a mesh
/// split among processes: inner nodes first as the tree lays them out, and each region's box.
struct RegionSplit {
  struct Node {
    int axis = -1; ///< -1 for a region
    float position = 0.f;
    int below = -1, above = -1; ///< children: axis < position, axis >= position
    int region = -1;
  };
  std::vector<Node> nodes; ///< the root first
  std::vector<Box3f> regions;
};
RegionSplit splitRegions(const MeshView &mesh, int count);

/// The scalar range of the cells each of the `count` partitions of the tree `nodes` lists, for `mesh`'s
/// field: what buildPartitions computed, again for new values on the same cells (the tree, boxes and step
/// scales depend on the cells alone).
void computePartitionValueRanges(const MeshView &mesh, std::span<const KdNode> nodes, uint32_t count,
                                 std::span<float> valueMin, std::span<float> valueMax);

/// The default `leafSize` makes about this many partitions (the median splits make 1-2 times as many leaves),
/// of at least kSmallestDefaultLeafSize cells (docs/design.md, "Choosing defaults"): a partition costs more
/// than a few samples (its traversal; on a GPU a warp waits for its slowest ray's), and much fewer partitions
/// leave the colour variance too coarse for the step sizes.
constexpr uint64_t kDefaultPartitions = 256;
constexpr uint32_t kSmallestDefaultLeafSize = 64;

/// The default leaf size for a mesh of `cells` cells.
inline uint32_t defaultLeafSize(uint64_t cells) {
  const uint64_t size = cells / kDefaultPartitions;
  return uint32_t(size < kSmallestDefaultLeafSize ? kSmallestDefaultLeafSize
                                                  : (size > UINT32_MAX ? UINT32_MAX : size));
}

// The steps of the build that the host's and the GPU's share, so that both make the same partitions.

/// Where a cell sits for the median splits: its box's centre, with -0 made +0 so that orders by value and by
/// bit pattern agree. Ties are broken by cell index, which makes the tree independent of how it is built.
UVR_HOST_DEVICE inline Vec3f partitionCentroid(const Box3f &cellBox) {
  const Vec3f c = cellBox.center();
  return {c.x + 0.f, c.y + 0.f, c.z + 0.f};
}

/// The axis along which points spanning `extent` spread most; the first of equals.
UVR_HOST_DEVICE inline int widestAxis(Vec3f extent) {
  return extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
}

/// How far the root box and every shrunk box reach past the cells: keeps samples on the outermost faces
/// inside, whatever the rounding of the slab test.
inline float partitionPadding(const Box3f &meshBounds) { return 1e-5f * length(meshBounds.size()) + 1e-30f; }

/// Deeper nodes are leaves whatever their cell count (identical centroids cannot be split anyway). Median
/// splits halve the cells at each level, so 32 levels hold the 2^32 cells that 32-bit indices can name; a
/// traversal's stack, one entry per level at most, stays as small (on a GPU it lives in local memory).
constexpr int kMaxPartitionDepth = 32;

/// log2 of the volume of a cell's box in 1/256ths, read off the float's exponent and mantissa (within 0.09
/// of log2, and the same on host and GPU, so that both builds scale steps alike): what a partition's step
/// scale averages. A flat box counts as a sixteenth of its longest side thick.
UVR_HOST_DEVICE inline int32_t cellSizeLog2(const Box3f &box) {
  const Vec3f e = box.upper - box.lower;
  const float thinnest = maxf(maxf(e.x, maxf(e.y, e.z)) * (1.f / 16.f), 1e-12f);
  const float volume = maxf(e.x, thinnest) * maxf(e.y, thinnest) * maxf(e.z, thinnest);
  uint32_t bits;
  memcpy(&bits, &volume, sizeof bits);
  return (int32_t(bits) - (127 << 23)) >> 15;
}

struct StepScales {
  std::vector<float> partition, node; ///< PartitionArrays::stepScale and nodeMaxStepScale
  float finest = 1.f;
  double mean = 0.0; ///< the mesh's mean cellSizeLog2 the scales compare with
};

/// The partitions' step scales from the sums of cellSizeLog2 over each partition's `cellCounts` cells: the
/// ratio of the geometric mean cell size in a partition to the mesh's, rounded to a power of two from 1/8 to
/// 8 (a partition whose cells are within a factor of 1.41 of the mesh's keeps steps of s1). On the host for
/// both builds, in integers to the rounding: both scale alike. `reference`: the mesh's mean cellSizeLog2
/// (MeshView::stepScaleReference), or NaN to take it from the sums.
StepScales computeStepScales(const std::vector<int64_t> &sizeLog2Sums,
                             const std::vector<uint64_t> &cellCounts, const std::vector<KdNode> &nodes,
                             double reference = NAN);

/// The scalar range a cell contributes to its partitions: empty where it holds only NaN, [0, 0] for geometry
/// alone (no field).
UVR_HOST_DEVICE inline void cellValueRange(const MeshView &mesh, uint64_t c, float &lo, float &hi) {
  if (!mesh.values) {
    lo = hi = 0.f;
  } else if (mesh.cellCentered) {
    const float value = mesh.values[c];
    lo = value == value ? value : INFINITY;
    hi = value == value ? value : -INFINITY;
  } else {
    lo = INFINITY;
    hi = -INFINITY;
    forEachCellVertex(mesh, c, [&](uint32_t v) {
      // fminf/fmaxf skip NaN, so one NaN vertex cannot poison the range.
      lo = fminf(lo, mesh.values[v]);
      hi = fmaxf(hi, mesh.values[v]);
    });
  }
}

/// Calls `visit(partition)` for every leaf that a cell with box `box` touches (a cell straddling leaves is
/// listed in each, paper §2.1). Most cells go down one side of every split: the descent pushes only where a
/// box straddles.
template <typename Visit>
UVR_HOST_DEVICE void forEachLeafTouching(const KdNode *nodes, const Box3f &box, Visit &&visit) {
  const float lower[3] = {box.lower.x, box.lower.y, box.lower.z};
  const float upper[3] = {box.upper.x, box.upper.y, box.upper.z};
  constexpr int kStackSize = 64;
  uint32_t stack[kStackSize];
  int top = 0;
  uint32_t node = 0;
  while (true) {
    const KdNode &n = nodes[node];
    if (n.axis == KdNode::kLeaf) {
      visit(n.child);
    } else {
      const bool below = lower[n.axis] <= n.split, above = upper[n.axis] >= n.split;
      if (below && above && top < kStackSize)
        stack[top++] = n.child + 1;
      if (below || above) {
        node = below ? n.child : n.child + 1;
        continue;
      }
    }
    if (top == 0)
      return;
    node = stack[--top];
  }
}

/// Visits the partitions that the ray [tMin, tMax] crosses, front to back, as `visit(node, t0, t1)` with a
/// leaf node and the ray's exact interval inside it; stops when `visit` returns false. Neighbouring leaves
/// share the split's t, so the intervals tile the ray with neither gaps nor overlaps. An inner node for which
/// `whole(node)` holds is visited as one interval instead of leaf by leaf (its partitions all drawn alike:
/// splitting the ray at their boundaries would change nothing but the cost). With `nodeMaxOpacity` (per node,
/// for the current transfer function), whole subtrees that are transparent or whose cells the ray misses are
/// skipped without visiting their leaves, and each interval is clipped to its node's shrunk box (paper §2.2).
/// After the last, where `end(t0, t1)` gives one, a last interval past the partitions, as node KdNode::kNone:
/// from the same call of `visit`, which a GPU kernel then inlines once.
template <typename Whole, typename Visit, typename End>
UVR_HOST_DEVICE void traversePartitions(const PartitionsView &parts, const Ray &ray, float tMin, float tMax,
                                        const float *nodeMaxOpacity, Whole &&whole, Visit &&visit,
                                        End &&end) {
  constexpr int kStackSize = kMaxPartitionDepth;
  struct Entry {
    uint32_t node;
    float t0, t1;
  };
  Entry stack[kStackSize];
  int top = 0;
  uint32_t node = 0;
  float t0 = tMin, t1 = tMax;
  bool ending = false;
  while (true) {
    float b0 = t0, b1 = t1; // what a visit gets: clipped to the node's shrunk box when culling
    bool culled = false;
    if (!ending) {
      culled = nodeMaxOpacity &&
               (nodeMaxOpacity[node] <= 0.f || !intersectBox(ray, parts.nodeBounds[node], t0, t1, b0, b1));
      const KdNode &n = parts.nodes[node];
      if (!culled && n.axis != KdNode::kLeaf && !whole(node)) {
        const int axis = int(n.axis);
        const float origin = ray.origin[axis];
        const float direction = ray.direction[axis];
        // The side holding the origin comes first; a ray lying in the plane belongs to the upper side.
        const bool originBelow = origin < n.split || (origin == n.split && direction < 0.f);
        const uint32_t nearChild = originBelow ? n.child : n.child + 1;
        const uint32_t farChild = originBelow ? n.child + 1 : n.child;
        if (direction == 0.f) {
          node = origin < n.split ? n.child : n.child + 1;
        } else {
          const float tSplit = (n.split - origin) * ray.invDirection[axis];
          if (tSplit >= t1 || tSplit <= 0.f) {
            node = nearChild;
          } else if (tSplit <= t0) {
            node = farChild;
          } else {
            if (top < kStackSize)
              stack[top++] = {farChild, tSplit, t1};
            node = nearChild;
            t1 = tSplit;
          }
        }
        continue;
      }
    }
    if ((ending || (!culled && b0 < b1)) && !visit(node, b0, b1))
      return;
    if (ending)
      return;
    if (top == 0) {
      if (!end(t0, t1))
        return;
      ending = true;
      node = KdNode::kNone;
      continue;
    }
    --top;
    node = stack[top].node;
    t0 = stack[top].t0;
    t1 = stack[top].t1;
  }
}

} // namespace uvr
