// The partitions' metadata for the current transfer function (SceneView's sigma, nodeMaxOpacity and
// nodeMinSigma), computed on the GPU as computePartitionMetadata does on the host.
#pragma once

#include "backend/cuda/device_buffer.cuh"
#include "render/integrator.h"

#include <cstddef>
#include <cstdint>

namespace uvr {

/// What the partitions' metadata is normalised by, reduced over all partitions. Non-negative floats order
/// as their bit patterns, which lets integer atomics take their minimum and maximum.
struct MetadataTotals {
  uint32_t lowestVariance;  ///< bits of the smallest variance over the partitions drawn
  uint32_t highestVariance; ///< bits of the largest
  uint32_t transparent;     ///< partitions the transfer function makes fully transparent, with no surface
};

class DeviceMetadata {
public:
  /// Sizes the arrays for `scene`'s partitions and KD tree (`nodeCount` nodes), links each node to its
  /// parent and each partition to its leaf, and points `scene` at the arrays.
  void link(SceneView &scene, uint32_t nodeCount);
  /// Recomputes the metadata for the transfer function `tf` and the isosurfaces `iso` (as
  /// computePartitionMetadata); returns the number of partitions skipped: fully transparent, no surface.
  uint32_t update(const TransferFunctionRangeView &tf, const PartitionsView &partitions,
                  const IsoSettings &iso);
  /// Copies the metadata of the last update back, for the `count` partitions.
  PartitionMetadata download(uint32_t count) const;
  size_t bytes() const;

private:
  DeviceBuffer<float> nodeMaxOpacity, nodeMinSigma, sigma;
  DeviceBuffer<uint32_t> kdParents, partitionNodes;
  DeviceBuffer<MetadataTotals> totals;
};

} // namespace uvr
