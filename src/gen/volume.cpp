#include "gen/volume.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace uvr {

float otsuThreshold(const Volume &volume) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float v : volume.values)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (!(lo < hi))
    return lo <= hi ? lo : 0.f;
  constexpr int kBins = 256;
  std::vector<double> histogram(kBins, 0.0);
  const double scale = kBins / (double(hi) - lo);
  for (float v : volume.values)
    if (std::isfinite(v))
      histogram[std::min(kBins - 1, int((double(v) - lo) * scale))] += 1.0;
  double total = 0, sum = 0;
  for (int b = 0; b < kBins; ++b) {
    total += histogram[b];
    sum += b * histogram[b];
  }
  double weightBelow = 0, sumBelow = 0, best = -1;
  int bestBin = 0;
  for (int b = 0; b < kBins - 1; ++b) {
    weightBelow += histogram[b];
    sumBelow += b * histogram[b];
    const double weightAbove = total - weightBelow;
    if (weightBelow == 0 || weightAbove == 0)
      continue;
    const double meanBelow = sumBelow / weightBelow, meanAbove = (sum - sumBelow) / weightAbove;
    const double between = weightBelow * weightAbove * (meanBelow - meanAbove) * (meanBelow - meanAbove);
    if (between > best) {
      best = between;
      bestBin = b;
    }
  }
  // The split lies at the upper edge of the last bin of the lower class.
  return float(lo + (bestBin + 1) / scale);
}

RangePyramid::RangePyramid(const Volume &volume) : volume_(volume) {
  std::array<int64_t, 3> dims = volume.dims;
  const std::vector<float> *belowMin = &volume.values, *belowMax = &volume.values;
  while (dims[0] > 1 || dims[1] > 1 || dims[2] > 1) {
    Level level;
    for (int a = 0; a < 3; ++a)
      level.dims[a] = (dims[a] + 1) / 2;
    const uint64_t count = uint64_t(level.dims[0]) * uint64_t(level.dims[1]) * uint64_t(level.dims[2]);
    level.min.resize(count);
    level.max.resize(count);
    tbb::parallel_for(int64_t(0), level.dims[2], [&](int64_t k) {
      for (int64_t j = 0; j < level.dims[1]; ++j)
        for (int64_t i = 0; i < level.dims[0]; ++i) {
          float lo = std::numeric_limits<float>::infinity(), hi = -lo;
          for (int64_t z = 2 * k; z < std::min(2 * k + 2, dims[2]); ++z)
            for (int64_t y = 2 * j; y < std::min(2 * j + 2, dims[1]); ++y)
              for (int64_t x = 2 * i; x < std::min(2 * i + 2, dims[0]); ++x) {
                const uint64_t below =
                    uint64_t(x) + uint64_t(dims[0]) * (uint64_t(y) + uint64_t(dims[1]) * z);
                lo = minf(lo, (*belowMin)[below]);
                hi = maxf(hi, (*belowMax)[below]);
              }
          const uint64_t here =
              uint64_t(i) + uint64_t(level.dims[0]) * (uint64_t(j) + uint64_t(level.dims[1]) * k);
          level.min[here] = lo;
          level.max[here] = hi;
        }
    });
    levels_.push_back(std::move(level));
    belowMin = &levels_.back().min;
    belowMax = &levels_.back().max;
    dims = levels_.back().dims;
  }
}

void RangePyramid::range(std::array<int64_t, 3> lo, std::array<int64_t, 3> hi, float &min, float &max) const {
  int64_t extent = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::clamp<int64_t>(lo[a], 0, volume_.dims[a] - 1);
    hi[a] = std::clamp<int64_t>(hi[a], lo[a], volume_.dims[a] - 1);
    extent = std::max(extent, hi[a] - lo[a] + 1);
  }
  // Blocks of at most a quarter of the box: at most 6 per axis, reaching at most half the box beyond it.
  int level = -1;
  while (level + 1 < int(levels_.size()) && (int64_t(8) << (level + 1)) <= extent)
    ++level;
  min = std::numeric_limits<float>::infinity();
  max = -min;
  if (level < 0) {
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
      for (int64_t y = lo[1]; y <= hi[1]; ++y)
        for (int64_t x = lo[0]; x <= hi[0]; ++x) {
          const float v = volume_.at(x, y, z);
          min = minf(min, v);
          max = maxf(max, v);
        }
    return;
  }
  const Level &l = levels_[level];
  const int shift = level + 1;
  for (int64_t z = lo[2] >> shift; z <= hi[2] >> shift; ++z)
    for (int64_t y = lo[1] >> shift; y <= hi[1] >> shift; ++y)
      for (int64_t x = lo[0] >> shift; x <= hi[0] >> shift; ++x) {
        const uint64_t index = uint64_t(x) + uint64_t(l.dims[0]) * (uint64_t(y) + uint64_t(l.dims[1]) * z);
        min = minf(min, l.min[index]);
        max = maxf(max, l.max[index]);
      }
}

} // namespace uvr
