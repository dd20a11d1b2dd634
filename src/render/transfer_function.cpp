#include "render/transfer_function.h"

#include <uvr/error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace uvr {

TransferFunction::TransferFunction(const ColorMap &map, float valueMin, float valueMax, int tableSize)
    : table_(sampleColorMap(map, std::max(tableSize, 2))), valueMin_(valueMin), valueMax_(valueMax) {
  if (!(valueMax >= valueMin) || !std::isfinite(valueMin) || !std::isfinite(valueMax))
    throw Error("invalid transfer-function range [" + std::to_string(valueMin) + ", " +
                std::to_string(valueMax) + "]");
  const size_t n = table_.size();
  prefixSum_.assign(4 * (n + 1), 0.0);
  prefixSquares_.assign(4 * (n + 1), 0.0);
  for (size_t i = 0; i < n; ++i) {
    const double channel[4] = {table_[i].x, table_[i].y, table_[i].z, table_[i].w};
    for (int k = 0; k < 4; ++k) {
      prefixSum_[4 * (i + 1) + size_t(k)] = prefixSum_[4 * i + size_t(k)] + channel[k];
      prefixSquares_[4 * (i + 1) + size_t(k)] = prefixSquares_[4 * i + size_t(k)] + channel[k] * channel[k];
    }
  }
  // Opacity 1 would make the extinction infinite; within a unit distance this one is opaque to 1e-6.
  constexpr float kMostOpaque = 1.f - 1e-6f;
  extinction_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec4f &c = table_[i];
    const float tau = -std::log1p(-std::min(c.w, kMostOpaque));
    extinction_[i] = {tau * c.x, tau * c.y, tau * c.z, tau};
  }
  // Summed in double, kept in float: the integrator reads differences over at least one entry.
  extinctionIntegral_.assign(n, Vec4f{});
  double sum[4] = {0.0, 0.0, 0.0, 0.0};
  for (size_t i = 1; i < n; ++i) {
    const Vec4f &a = extinction_[i - 1], &b = extinction_[i];
    sum[0] += 0.5 * (double(a.x) + b.x);
    sum[1] += 0.5 * (double(a.y) + b.y);
    sum[2] += 0.5 * (double(a.z) + b.z);
    sum[3] += 0.5 * (double(a.w) + b.w);
    extinctionIntegral_[i] = {float(sum[0]), float(sum[1]), float(sum[2]), float(sum[3])};
  }
  // Level k holds the maximum over 2^k entries from each position; positions past n - 2^k stay zero.
  const size_t levels = size_t(std::bit_width(n));
  opacityMax_.assign(levels * n, 0.f);
  for (size_t i = 0; i < n; ++i)
    opacityMax_[i] = table_[i].w;
  for (size_t k = 1; k < levels; ++k) {
    const float *previous = opacityMax_.data() + (k - 1) * n;
    float *level = opacityMax_.data() + k * n;
    const size_t half = size_t(1) << (k - 1);
    for (size_t i = 0; i + 2 * half <= n; ++i)
      level[i] = std::max(previous[i], previous[i + half]);
  }
}

TransferFunctionView TransferFunction::view() const {
  const float span = valueMax_ - valueMin_;
  const float scale = span > 0.f ? float(table_.size() - 1) / span : 0.f;
  return {table_.data(), int(table_.size()), valueMin_,
          scale,         extinction_.data(), extinctionIntegral_.data()};
}

TransferFunctionRangeView TransferFunction::rangeView() const {
  return {view(),          prefixSum_.data(), prefixSquares_.data(), opacityMax_.data(),
          varianceLowest_, varianceHighest_};
}

PartitionMetadata computePartitionMetadata(const Partitions &partitions, const TransferFunction &tf,
                                           const IsoSettings *iso) {
  const uint32_t count = partitions.count();
  PartitionMetadata meta;
  meta.maxOpacity.resize(count);
  meta.sigma.resize(count);
  std::vector<float> variance(count);
  const TransferFunctionRangeView ranges = tf.rangeView();
  const bool hidden = iso && iso->hideVolume;
  tbb::parallel_for(uint32_t(0), count, [&](uint32_t i) {
    meta.maxOpacity[i] = hidden ? 0.f : ranges.maxOpacity(partitions.valueMin[i], partitions.valueMax[i]);
    variance[i] = ranges.colorVariance(partitions.valueMin[i], partitions.valueMax[i]);
  });

  // Normalise by the extremes over the partitions that are drawn at all (paper §2.1).
  float lowest = INFINITY, highest = -INFINITY;
  for (uint32_t i = 0; i < count; ++i) {
    if (meta.maxOpacity[i] > 0.f) {
      lowest = std::min(lowest, variance[i]);
      highest = std::max(highest, variance[i]);
    }
  }
  meta.varianceLowest = lowest;
  meta.varianceHighest = highest;
  if (!std::isnan(ranges.varianceLowest)) {
    lowest = ranges.varianceLowest;
    highest = ranges.varianceHighest;
  }
  for (uint32_t i = 0; i < count; ++i) {
    meta.sigma[i] = normalizedSigma(variance[i], lowest, highest);
    // After the normalisation: the surfaces change which partitions are marched, not the volume's steps.
    if (iso && !(meta.maxOpacity[i] > 0.f) &&
        iso->crossesRange(partitions.valueMin[i], partitions.valueMax[i]))
      meta.maxOpacity[i] = kIsoVisitOpacity;
    if (!(meta.maxOpacity[i] > 0.f))
      ++meta.transparentCount;
  }

  meta.nodeMaxOpacity.resize(partitions.nodes.size());
  meta.nodeMinSigma.resize(partitions.nodes.size());
  for (size_t node = partitions.nodes.size(); node-- > 0;) { // children follow their parents
    const KdNode &n = partitions.nodes[node];
    if (n.axis == KdNode::kLeaf) {
      meta.nodeMaxOpacity[node] = meta.maxOpacity[n.child];
      meta.nodeMinSigma[node] = meta.maxOpacity[n.child] > 0.f ? meta.sigma[n.child] : kTransparentSigma;
    } else {
      meta.nodeMaxOpacity[node] = std::max(meta.nodeMaxOpacity[n.child], meta.nodeMaxOpacity[n.child + 1]);
      meta.nodeMinSigma[node] = std::min(meta.nodeMinSigma[n.child], meta.nodeMinSigma[n.child + 1]);
    }
  }
  return meta;
}

} // namespace uvr
