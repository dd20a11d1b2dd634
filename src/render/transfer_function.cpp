#include "render/transfer_function.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace uvr {

TransferFunction::TransferFunction(const ColorMap &map, float valueMin, float valueMax, int tableSize)
    : table_(sampleColorMap(map, std::max(tableSize, 2))), valueMin_(valueMin), valueMax_(valueMax) {
  if (!(valueMax >= valueMin) || !std::isfinite(valueMin) || !std::isfinite(valueMax))
    throw Error("invalid transfer-function range [" + std::to_string(valueMin) + ", " + std::to_string(valueMax) +
                "]");
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
  float result = 0.f;
  for (int i = first; i <= last; ++i)
    result = std::max(result, table_[size_t(i)].w);
  return result;
}

float TransferFunction::colorVariance(float a, float b) const {
  if (!(a <= b))
    return 0.f;
  int first, last;
  entryRange(a, b, first, last);
  double sum[4] = {}, sumSquares[4] = {};
  for (int i = first; i <= last; ++i) {
    const Vec4f &c = table_[size_t(i)];
    const double channel[4] = {c.x, c.y, c.z, c.w};
    for (int k = 0; k < 4; ++k) {
      sum[k] += channel[k];
      sumSquares[k] += channel[k] * channel[k];
    }
  }
  const double n = double(last - first + 1);
  double variance = 0.0;
  for (int k = 0; k < 4; ++k)
    variance += std::max(0.0, sumSquares[k] / n - (sum[k] / n) * (sum[k] / n));
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
  const float span = highest - lowest;
  for (uint32_t i = 0; i < count; ++i)
    meta.sigma[i] = span > 0.f ? std::sqrt(std::clamp((variance[i] - lowest) / span, 0.f, 1.f)) : 1.f;
  return meta;
}

} // namespace uvr
