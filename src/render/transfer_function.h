// The transfer function as the integrator reads it (an RGBA table over a scalar range), and the per-partition
// metadata derived from it on every change (paper §2.1).
#pragma once

#include "accel/partitions.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "render/color_map.h"

#include <vector>

namespace uvr {

struct TransferFunctionView {
  const Vec4f *table = nullptr;
  int size = 0;
  float valueMin = 0.f;
  float scale = 0.f; ///< table entries per scalar unit

  /// Colour and opacity (per opacity unit distance) at `value`, clamped to the range; NaN is transparent.
  UVR_HOST_DEVICE Vec4f sample(float value) const {
    if (value != value)
      return {};
    const float x = clampf((value - valueMin) * scale, 0.f, float(size - 1));
    const int i = x >= float(size - 1) ? size - 2 : int(x);
    const float f = x - float(i);
    const Vec4f a = table[i], b = table[i + 1];
    return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f, a.w + (b.w - a.w) * f};
  }
};

/// A colour map stretched over [valueMin, valueMax] and sampled into a table.
class TransferFunction {
public:
  static constexpr int kDefaultTableSize = 1024;

  TransferFunction(const ColorMap &map, float valueMin, float valueMax, int tableSize = kDefaultTableSize);

  TransferFunctionView view() const;
  float valueMin() const { return valueMin_; }
  float valueMax() const { return valueMax_; }
  const std::vector<Vec4f> &table() const { return table_; }

  /// Highest opacity the function takes over [a, b]; never below the true maximum. Constant time.
  float maxOpacity(float a, float b) const;
  /// Variance of colour and opacity (summed over r, g, b, a) over [a, b]. Constant time.
  float colorVariance(float a, float b) const;

private:
  void entryRange(float a, float b, int &first, int &last) const;

  std::vector<Vec4f> table_;
  float valueMin_, valueMax_;
  // Prefix sums of each channel and its square, and a sparse table of opacity maxima (level k holds the
  // maximum over 2^k entries), so that a partition's metadata costs O(1) whatever its range.
  std::vector<double> prefixSum_, prefixSquares_; ///< 4 per entry, entry 0 = 0
  std::vector<std::vector<float>> opacityMax_;
};

/// What space skipping and adaptive sampling read per partition; recomputed on every transfer-function change
/// in time linear in table entries and partitions, independent of the cell count.
struct PartitionMetadata {
  std::vector<float> maxOpacity;
  std::vector<float> nodeMaxOpacity; ///< per KD node, the maximum over the partitions below
  std::vector<float> sigma;          ///< colour standard deviation, normalised over all partitions to [0, 1]
  uint32_t transparentCount = 0;
};

PartitionMetadata computePartitionMetadata(const Partitions &partitions, const TransferFunction &tf);

/// The paper's step size for a partition of normalised deviation `sigma` (§2.4).
UVR_HOST_DEVICE inline float adaptiveStepSize(float s1, float s2, float p, float sigma) {
  return maxf(s1 + (s2 - s1) * powf(fabsf(minf(sigma, 1.f) - 1.f), p), s1);
}

} // namespace uvr
