// The GPU's counterpart of accel/bvh_build.cpp: the point-location BVH, a radix tree over the cells in
// Morton order where the host's is Embree's.
#include "backend/cuda/device_builder.cuh"

#include "core/morton.h"
#include "mesh/cell.h"

#include <cub/device/device_scan.cuh>

namespace uvr::gpu_build {
namespace {

__global__ void mortonKernel(MeshView mesh, uint64_t cells, Vec3f origin, Vec3f scale, uint32_t *codes) {
  const uint64_t c = globalIndex();
  if (c >= cells)
    return;
  const Vec3f p = cellCentroid(mesh, c) - origin;
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

/// Internal node i's range and split, found where they are needed (twice) rather than kept: 12 bytes a cell.
__device__ inline RadixNode radixNode(const uint32_t *codes, int64_t cells, int64_t i) {
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
  return {first, last, uint32_t(gamma)};
}

/// Which internal nodes stay inner nodes after collapsing, one bit each, and their ranks among the kept ones:
/// per 32-bit word of bits, the kept nodes in the words before it. A rank then costs a popcount, and the
/// whole a sixteenth of a rank per node (the lean layout's build peaks here).
struct KeptNodes {
  const uint32_t *bits;
  const uint32_t *before; ///< one entry more than words: the last holds the kept count

  __device__ bool kept(int64_t i) const { return bits[i >> 5] >> (i & 31) & 1u; }
  __device__ uint32_t rank(int64_t i) const {
    return before[i >> 5] + uint32_t(__popc(bits[i >> 5] & ((1u << (i & 31)) - 1u)));
  }
};

/// The kept bits of internal nodes, a warp's 32 to a word, and each word's count (its rank once scanned).
/// Every thread of a warp takes part in the vote: the grid is whole warps.
__global__ void keptKernel(const uint32_t *codes, int64_t cells, uint32_t *bits, uint32_t *counts) {
  const int64_t i = int64_t(globalIndex());
  bool kept = false;
  if (i < cells - 1) {
    const RadixNode node = radixNode(codes, cells, i);
    kept = keptInner(node.first, node.last);
  }
  const uint32_t word = __ballot_sync(0xffffffffu, kept);
  if ((threadIdx.x & 31u) == 0 && i < cells - 1) {
    bits[i >> 5] = word;
    counts[i >> 5] = uint32_t(__popc(word));
  }
}

/// Per kept inner node, its children's records (boxes aside) and, for kept children, where they are stored.
__global__ void collapsedTreeKernel(const uint32_t *codes, int64_t cells, KeptNodes kept, BvhNode *nodes,
                                    uint32_t *parentSlot) {
  const int64_t i = int64_t(globalIndex());
  if (i >= cells - 1 || !kept.kept(i))
    return;
  const RadixNode node = radixNode(codes, cells, i);
  const uint32_t ranges[2][2] = {{node.first, node.split}, {node.split + 1, node.last}};
  for (int side = 0; side < 2; ++side) {
    const uint32_t slot = 1 + 2 * kept.rank(i) + uint32_t(side), first = ranges[side][0],
                   last = ranges[side][1];
    if (keptInner(first, last)) {
      const uint32_t child = kept.rank(side == 0 ? node.split : node.split + 1);
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
__global__ void collapsedBoundsKernel(MeshView mesh, const uint32_t *cellIds, int64_t cells, KeptNodes kept,
                                      BvhNode *nodes, const uint32_t *parentSlot, uint32_t *arrivals) {
  const int64_t i = int64_t(globalIndex());
  if (i >= cells - 1 || !kept.kept(i))
    return;
  const uint32_t self = kept.rank(i);
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

} // namespace

void DeviceBuilder::bvh() {
  DeviceBuffer<uint32_t> codes; // sorted, once the cells are
  codes.resize(cells_);
  const Vec3f extent = meshBounds_.size();
  auto scaleOf = [](float e) { return e > 0.f ? 1024.f / e : 0.f; };
  mortonKernel<<<cellBlocks(), kBlock>>>(mesh_, cells_, meshBounds_.lower,
                                         {scaleOf(extent.x), scaleOf(extent.y), scaleOf(extent.z)},
                                         codes.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  sortCells(codes, 30, out_.bvh.cellIds);
  if (cells_ <= kLeafCells) { // one leaf
    const BvhNode root{meshBounds_, 0, uint32_t(cells_)};
    out_.bvh.nodes.upload(&root, 1);
    return;
  }
  const int64_t inner = int64_t(cells_) - 1;
  const uint64_t words = (uint64_t(inner) + 31) / 32;
  DeviceBuffer<uint32_t> keptBits, keptBefore;
  keptBits.resize(words);
  keptBefore.resize(words + 1);
  UVR_CUDA_CHECK(cudaMemset(keptBefore.data() + words, 0, sizeof(uint32_t)));
  static_assert(kBlock % 32 == 0, "keptKernel votes in whole warps");
  keptKernel<<<blocksFor(inner, kBlock), kBlock>>>(codes.data(), int64_t(cells_), keptBits.data(),
                                                   keptBefore.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceScan::ExclusiveSum(storage, bytes, keptBefore.data(), keptBefore.data(),
                                         int64_t(words) + 1);
  });
  const KeptNodes kept{keptBits.data(), keptBefore.data()};
  const uint32_t keptCount = downloadOne(keptBefore.data() + words);
  out_.bvh.nodes.resize(1 + 2 * uint64_t(keptCount));
  const BvhNode root{Box3f{}, 1, 0}; // its box comes from below
  UVR_CUDA_CHECK(cudaMemcpy(out_.bvh.nodes.data(), &root, sizeof root, cudaMemcpyHostToDevice));
  DeviceBuffer<uint32_t> parentSlot, arrivals;
  parentSlot.resize(keptCount);
  collapsedTreeKernel<<<blocksFor(inner, kBlock), kBlock>>>(codes.data(), int64_t(cells_), kept,
                                                            out_.bvh.nodes.data(), parentSlot.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  codes.release();
  arrivals.resize(keptCount);
  UVR_CUDA_CHECK(cudaMemset(arrivals.data(), 0, arrivals.bytes()));
  collapsedBoundsKernel<<<blocksFor(inner, kBlock), kBlock>>>(mesh_, out_.bvh.cellIds.data(), int64_t(cells_),
                                                              kept, out_.bvh.nodes.data(), parentSlot.data(),
                                                              arrivals.data());
}

} // namespace uvr::gpu_build
