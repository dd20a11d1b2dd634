#include "render/transfer_function.h"

#include "core/error.h"

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
  opacityMax_.emplace_back(n);
  for (size_t i = 0; i < n; ++i)
    opacityMax_[0][i] = table_[i].w;
  for (size_t span = 2; span <= n; span *= 2) {
    const std::vector<float> &previous = opacityMax_.back();
    std::vector<float> level(n - span + 1);
    for (size_t i = 0; i < level.size(); ++i)
      level[i] = std::max(previous[i], previous[i + span / 2]);
    opacityMax_.push_back(std::move(level));
  }
}

TransferFunctionView TransferFunction::view() const {
  const float span = valueMax_ - valueMin_;
  const float scale = span > 0.f ? float(table_.size() - 1) / span : 0.f;
  return {table_.data(), int(table_.size()), valueMin_, scale};
}

void TransferFunction::entryRange(float a, float b, int &first, int &last) const {
  const TransferFunctionView v = view();
  const float lastEntry = float(v.size - 1);
  first = int(std::floor(std::clamp((a - v.valueMin) * v.scale, 0.f, lastEntry)));
  last = int(std::ceil(std::clamp((b - v.valueMin) * v.scale, 0.f, lastEntry)));
}

float TransferFunction::maxOpacity(float a, float b) const {
  if (!(a <= b))
    return 0.f; // no finite value in the range
  int first, last;
  entryRange(a, b, first, last);
  const auto count = unsigned(last - first + 1);
  const int level = std::bit_width(count) - 1; // two overlapping runs of 2^level entries cover [first, last]
  const std::vector<float> &maxima = opacityMax_[size_t(level)];
  return std::max(maxima[size_t(first)], maxima[size_t(last + 1 - (1 << level))]);
}

float TransferFunction::colorVariance(float a, float b) const {
  if (!(a <= b))
    return 0.f;
  int first, last;
  entryRange(a, b, first, last);
  const double n = double(last - first + 1);
  double variance = 0.0;
  for (size_t k = 0; k < 4; ++k) {
    const double sum = prefixSum_[4 * size_t(last + 1) + k] - prefixSum_[4 * size_t(first) + k];
    const double squares = prefixSquares_[4 * size_t(last + 1) + k] - prefixSquares_[4 * size_t(first) + k];
    variance += std::max(0.0, squares / n - (sum / n) * (sum / n));
  }
  return float(variance);
}

PartitionMetadata computePartitionMetadata(const Partitions &partitions, const TransferFunction &tf) {
  const uint32_t count = partitions.count();
  PartitionMetadata meta;
  meta.maxOpacity.resize(count);
  meta.sigma.resize(count);
  std::vector<float> variance(count);
  tbb::parallel_for(uint32_t(0), count, [&](uint32_t i) {
    meta.maxOpacity[i] = tf.maxOpacity(partitions.valueMin[i], partitions.valueMax[i]);
    variance[i] = tf.colorVariance(partitions.valueMin[i], partitions.valueMax[i]);
  });

  // Normalise by the extremes over the partitions that are drawn at all (paper §2.1).
  float lowest = INFINITY, highest = -INFINITY;
  for (uint32_t i = 0; i < count; ++i) {
    if (meta.maxOpacity[i] > 0.f) {
      lowest = std::min(lowest, variance[i]);
      highest = std::max(highest, variance[i]);
    } else {
      ++meta.transparentCount;
    }
  }
  meta.nodeMaxOpacity.resize(partitions.nodes.size());
  for (size_t node = partitions.nodes.size(); node-- > 0;) { // children follow their parents
    const KdNode &n = partitions.nodes[node];
    meta.nodeMaxOpacity[node] =
        n.axis == KdNode::kLeaf ? meta.maxOpacity[n.child]
                                : std::max(meta.nodeMaxOpacity[n.child], meta.nodeMaxOpacity[n.child + 1]);
  }

  const float span = highest - lowest;
  for (uint32_t i = 0; i < count; ++i)
    meta.sigma[i] = span > 0.f ? std::sqrt(std::clamp((variance[i] - lowest) / span, 0.f, 1.f)) : 1.f;
  return meta;
}

} // namespace uvr
