// Bounding volume hierarchy over the cells, for point location: flat arrays, usable on host and device.
#pragma once

#include "core/host_device.h"
#include "core/storage.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// A binary node: an inner node's children are nodes[first] and nodes[first + 1]; a leaf (count > 0) lists
/// cellIds[first, first + count).
struct BvhNode {
  Box3f bounds;
  uint32_t first = 0;
  uint32_t count = 0;
};

struct BvhView {
  const BvhNode *nodes = nullptr;
  const uint32_t *cellIds = nullptr;
};

template <typename Storage> struct BvhArrays {
  typename Storage::template Array<BvhNode> nodes;
  typename Storage::template Array<uint32_t> cellIds;

  BvhView view() const { return {nodes.data(), cellIds.data()}; }
  template <typename A, typename B, typename F> static void forEachMember(A &a, B &b, F &&f) {
    f(a.nodes, b.nodes);
    f(a.cellIds, b.cellIds);
  }
};
using Bvh = BvhArrays<HostStorage>;

/// Builds the hierarchy with Embree's SAH builder (all cores) and flattens it.
Bvh buildBvh(const MeshView &mesh);

/// Calls `visit(cell)` for every cell whose leaf box contains `p`, until it returns true. Returns whether
/// one did.
template <typename Visit> UVR_HOST_DEVICE bool findCell(const BvhView &bvh, Vec3f p, Visit &&visit) {
  constexpr int kStackSize = 64;
  uint32_t stack[kStackSize];
  int top = 0;
  uint32_t node = 0;
  if (!bvh.nodes[0].bounds.contains(p))
    return false;
  while (true) {
    const BvhNode &n = bvh.nodes[node];
    if (n.count > 0) {
      for (uint32_t i = 0; i < n.count; ++i)
        if (visit(bvh.cellIds[n.first + i]))
          return true;
    } else {
      const bool inLeft = bvh.nodes[n.first].bounds.contains(p);
      const bool inRight = bvh.nodes[n.first + 1].bounds.contains(p);
      if (inLeft && inRight && top < kStackSize) {
        stack[top++] = n.first + 1;
        node = n.first;
        continue;
      }
      if (inLeft || inRight) {
        node = inLeft ? n.first : n.first + 1;
        continue;
      }
    }
    if (top == 0)
      return false;
    node = stack[--top];
  }
}

} // namespace uvr
