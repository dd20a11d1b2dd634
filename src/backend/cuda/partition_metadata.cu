#include "backend/cuda/partition_metadata.cuh"

#include <cub/block/block_reduce.cuh>

#include <cstring>
#include <vector>

namespace uvr {
namespace {

constexpr MetadataTotals kEmptyTotals{0x7f800000u /* +inf */, 0u, 0u};
constexpr int kMetadataBlock = 256;

/// Links each KD node to its parent and each partition to its leaf node, for the metadata kernel's walk up.
__global__ void linkNodesKernel(const KdNode *nodes, uint32_t nodeCount, uint32_t *parents,
                                uint32_t *partitionNodes) {
  const uint32_t node = blockIdx.x * blockDim.x + threadIdx.x;
  if (node >= nodeCount)
    return;
  const KdNode n = nodes[node];
  if (n.axis == KdNode::kLeaf) {
    partitionNodes[n.child] = node;
  } else {
    parents[n.child] = node;
    parents[n.child + 1] = node;
  }
}

/// Per partition, as computePartitionMetadata on the host: the maximum opacity (at its leaf node, and raised
/// into the nodes above, zeroed beforehand; kIsoVisitOpacity for a transparent one that holds a surface) and
/// the colour variance (into `variance`, normalised by normalizeSigmaKernel).
__global__ void partitionMetadataKernel(TransferFunctionRangeView tf, PartitionsView parts,
                                        const uint32_t *parents, const uint32_t *partitionNodes,
                                        float *variance, float *nodeMaxOpacity, MetadataTotals *totals,
                                        IsoSettings iso) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  bool drawn = false, marched = false;
  float v = 0.f;
  if (i < parts.count) {
    const float opacity =
        iso.hideVolume ? 0.f : maxf(tf.maxOpacity(parts.valueMin[i], parts.valueMax[i]), 0.f);
    v = tf.colorVariance(parts.valueMin[i], parts.valueMax[i]);
    variance[i] = v;
    drawn = opacity > 0.f;
    const float visit =
        drawn || !iso.crossesRange(parts.valueMin[i], parts.valueMax[i]) ? opacity : kIsoVisitOpacity;
    marched = visit > 0.f;
    // Raise the nodes above to this maximum; stop at one that holds as much already: whoever raised it
    // carries that value on to the root.
    uint32_t node = partitionNodes[i];
    nodeMaxOpacity[node] = visit;
    const uint32_t bits = __float_as_uint(visit);
    while (marched && node != 0) {
      node = parents[node];
      if (atomicMax(reinterpret_cast<uint32_t *>(nodeMaxOpacity + node), bits) >= bits)
        break;
    }
  }
  using Reduce = cub::BlockReduce<uint32_t, kMetadataBlock>;
  __shared__ typename Reduce::TempStorage storage;
  const uint32_t varianceBits = __float_as_uint(v);
  const uint32_t lowest = Reduce(storage).Reduce(drawn ? varianceBits : kEmptyTotals.lowestVariance,
                                                 [](uint32_t a, uint32_t b) { return a < b ? a : b; });
  __syncthreads();
  const uint32_t highest =
      Reduce(storage).Reduce(drawn ? varianceBits : 0u, [](uint32_t a, uint32_t b) { return a > b ? a : b; });
  __syncthreads();
  const uint32_t transparent = Reduce(storage).Sum(i < parts.count && !marched ? 1u : 0u);
  if (threadIdx.x == 0) {
    atomicMin(&totals->lowestVariance, lowest);
    atomicMax(&totals->highestVariance, highest);
    atomicAdd(&totals->transparent, transparent);
  }
}

/// Per partition, its sigma from the variance in `sigma`, lowered into the nodes above it as their
/// nodeMinSigma (set above any sigma beforehand). Sigmas and kTransparentSigma order as their bits do as
/// signed integers, which lets integer atomics take their minimum.
__global__ void normalizeSigmaKernel(uint32_t count, const MetadataTotals *totals, float givenLowest,
                                     float givenHighest, const uint32_t *parents,
                                     const uint32_t *partitionNodes, const float *nodeMaxOpacity,
                                     float *sigma, float *nodeMinSigma) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= count)
    return;
  // The extremes given (a piece of a mesh takes the whole mesh's), else the partitions' own.
  const bool given = !isnan(givenLowest);
  sigma[i] = normalizedSigma(sigma[i], given ? givenLowest : __uint_as_float(totals->lowestVariance),
                             given ? givenHighest : __uint_as_float(totals->highestVariance));
  uint32_t node = partitionNodes[i];
  const float lowest = nodeMaxOpacity[node] > 0.f ? sigma[i] : kTransparentSigma;
  nodeMinSigma[node] = lowest;
  const int bits = __float_as_int(lowest);
  while (node != 0) {
    node = parents[node];
    if (atomicMin(reinterpret_cast<int *>(nodeMinSigma + node), bits) <= bits)
      break;
  }
}

} // namespace

void DeviceMetadata::link(SceneView &scene, uint32_t nodeCount) {
  const uint32_t partitionCount = scene.partitions.count;
  kdParents.resize(nodeCount);
  partitionNodes.resize(partitionCount);
  linkNodesKernel<<<blocksFor(nodeCount, kMetadataBlock), kMetadataBlock>>>(
      scene.partitions.nodes, nodeCount, kdParents.data(), partitionNodes.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  sigma.resize(partitionCount);
  nodeMaxOpacity.resize(nodeCount);
  nodeMinSigma.resize(nodeCount);
  totals.resize(1);
  scene.sigma = sigma.data();
  scene.nodeMaxOpacity = nodeMaxOpacity.data();
  scene.nodeMinSigma = nodeMinSigma.data();
}

uint32_t DeviceMetadata::update(const TransferFunctionRangeView &tf, const PartitionsView &partitions,
                                const IsoSettings &iso) {
  const uint32_t count = partitions.count;
  UVR_CUDA_CHECK(cudaMemset(nodeMaxOpacity.data(), 0, nodeMaxOpacity.bytes()));
  UVR_CUDA_CHECK(cudaMemcpy(totals.data(), &kEmptyTotals, sizeof kEmptyTotals, cudaMemcpyHostToDevice));
  partitionMetadataKernel<<<blocksFor(count, kMetadataBlock), kMetadataBlock>>>(
      tf, partitions, kdParents.data(), partitionNodes.data(), sigma.data(), nodeMaxOpacity.data(),
      totals.data(), iso);
  UVR_CUDA_CHECK(cudaGetLastError());
  UVR_CUDA_CHECK(cudaMemset(nodeMinSigma.data(), 0x7f, nodeMinSigma.bytes())); // 3.4e38, above any sigma
  normalizeSigmaKernel<<<blocksFor(count, kMetadataBlock), kMetadataBlock>>>(
      count, totals.data(), tf.varianceLowest, tf.varianceHighest, kdParents.data(), partitionNodes.data(),
      nodeMaxOpacity.data(), sigma.data(), nodeMinSigma.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  MetadataTotals reduced{};
  totals.download(&reduced, 1); // waits for the kernels; a fault surfaces here
  return reduced.transparent;
}

PartitionMetadata DeviceMetadata::download(uint32_t count) const {
  PartitionMetadata meta;
  meta.sigma.resize(count);
  meta.nodeMaxOpacity.resize(nodeMaxOpacity.bytes() / sizeof(float));
  meta.nodeMinSigma.resize(meta.nodeMaxOpacity.size());
  sigma.download(meta.sigma.data(), count);
  nodeMaxOpacity.download(meta.nodeMaxOpacity.data(), meta.nodeMaxOpacity.size());
  nodeMinSigma.download(meta.nodeMinSigma.data(), meta.nodeMinSigma.size());
  // A partition's maximum is its leaf node's.
  std::vector<uint32_t> leafNodes(count);
  partitionNodes.download(leafNodes.data(), count);
  meta.maxOpacity.resize(count);
  for (uint32_t i = 0; i < count; ++i)
    meta.maxOpacity[i] = meta.nodeMaxOpacity[leafNodes[i]];
  MetadataTotals reduced{};
  totals.download(&reduced, 1);
  meta.transparentCount = reduced.transparent;
  if (reduced.lowestVariance != kEmptyTotals.lowestVariance) { // a partition is drawn
    std::memcpy(&meta.varianceLowest, &reduced.lowestVariance, sizeof(float));
    std::memcpy(&meta.varianceHighest, &reduced.highestVariance, sizeof(float));
  }
  return meta;
}

size_t DeviceMetadata::bytes() const {
  return nodeMaxOpacity.bytes() + nodeMinSigma.bytes() + sigma.bytes() + kdParents.bytes() +
         partitionNodes.bytes() + totals.bytes();
}

} // namespace uvr
