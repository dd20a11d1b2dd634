// The transfer function as the integrator reads it (an RGBA table over a scalar range), and the per-partition
// metadata derived from it on every change (paper §2.1).
#pragma once

#include "accel/partitions.h"
#include "core/color_map.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "render/isosurface.h"

#include <cmath>
#include <vector>

namespace uvr {

/// Opacity correction (paper §2.4): the opacity of a sample that stands for `distance` along the ray, where
/// the transfer function gives `alpha` per `unit` distance.
UVR_HOST_DEVICE inline float correctedOpacity(float alpha, float distance, float unit) {
  const float exponent = distance / unit;
  // At the default unit, s1, fixed steps need no correction, and powf is costly on a CPU.
  return exponent == 1.f ? minf(alpha, 1.f) : 1.f - powf(maxf(1.f - alpha, 0.f), exponent);
}

struct TransferFunctionView {
  const Vec4f *table = nullptr;
  int size = 0;
  float valueMin = 0.f;
  float scale = 0.f; ///< table entries per scalar unit
  /// Per entry, (tau r, tau g, tau b, tau) with the extinction tau = -ln(1 - opacity); and their integrals
  /// from entry 0 over the table's linear pieces (for integrate).
  const Vec4f *extinction = nullptr;
  const Vec4f *extinctionIntegral = nullptr;

  /// Colour and opacity (per opacity unit distance) at `value`, clamped to the range; NaN is transparent.
  UVR_HOST_DEVICE Vec4f sample(float value) const { return lookup(table, value); }

  /// Extinction (-ln(1 - opacity), per opacity unit distance) at `value`, as step takes it.
  UVR_HOST_DEVICE float extinctionAt(float value) const { return lookup(extinction, value).w; }

  /// Colour (rgb) and opacity of a ray segment over which the scalar is `a` for `lengthA`, then `b` for
  /// `lengthB` (a cell field's step): the optical depth of both pieces from the extinction at their values
  /// (interpolated in the table), and, as integrate, the colour the extinction-weighted mean, without the
  /// attenuation within the segment. NaN is transparent.
  UVR_HOST_DEVICE Vec4f step(float a, float b, float lengthA, float lengthB, float unit) const {
    const Vec4f ea = lookup(extinction, a), eb = lookup(extinction, b);
    const Vec4f sum = {ea.x * lengthA + eb.x * lengthB, ea.y * lengthA + eb.y * lengthB,
                       ea.z * lengthA + eb.z * lengthB, ea.w * lengthA + eb.w * lengthB};
    if (!(sum.w > 0.f))
      return {};
    const float w = 1.f / sum.w;
    return {sum.x * w, sum.y * w, sum.z * w, 1.f - expf(-sum.w / unit)};
  }

  /// Colour (rgb) and opacity of a ray segment `distance` long over which the scalar runs linearly from `a`
  /// to `b`: the function integrated over the values between (pre-integration, Engel et al. 2001, with the
  /// colour weighted by extinction rather than attenuated within the segment). The optical depth is exact
  /// for the table's linear pieces, so a long step misses no peak of the function between its two samples.
  UVR_HOST_DEVICE Vec4f integrate(float a, float b, float distance, float unit) const {
    a = a != a ? b : a; // NaN: the other end's value, as far as it goes
    b = b != b ? a : b;
    if (a != a)
      return {};
    const float xa = (a - valueMin) * scale, xb = (b - valueMin) * scale;
    const float span = xb - xa;
    // Within one entry the table is linear: its value at the middle is as good, and the difference of the
    // integrals below would lose digits.
    if (!(fabsf(span) >= 1.f)) {
      const Vec4f c = sample(0.5f * (a + b));
      return {c.x, c.y, c.z, correctedOpacity(c.w, distance, unit)};
    }
    const Vec4f ia = integralTo(xa), ib = integralTo(xb);
    const float depth = (ib.w - ia.w) / span; // mean extinction
    if (!(depth > 0.f))
      return {};
    const float w = 1.f / (ib.w - ia.w);
    return {(ib.x - ia.x) * w, (ib.y - ia.y) * w, (ib.z - ia.z) * w, 1.f - expf(-depth * (distance / unit))};
  }

private:
  /// A table's entries (`table`'s, or `extinction`'s) interpolated to `value`, clamped to the range; zero for
  /// NaN.
  UVR_HOST_DEVICE Vec4f lookup(const Vec4f *entries, float value) const {
    if (value != value)
      return {};
    const float x = clampf((value - valueMin) * scale, 0.f, float(size - 1));
    const int i = x >= float(size - 1) ? size - 2 : int(x);
    const float f = x - float(i);
    const Vec4f a = entries[i], b = entries[i + 1];
    return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f, a.w + (b.w - a.w) * f};
  }

  /// The integrals of the extinction entries from entry 0 to table position x; beyond the table the end
  /// entries' values hold, as sample clamps.
  UVR_HOST_DEVICE Vec4f integralTo(float x) const {
    const int last = size - 1;
    const float clamped = clampf(x, 0.f, float(last));
    const int i = clamped >= float(last) ? last - 1 : int(clamped);
    const float f = clamped - float(i), g = 0.5f * f * f;
    const Vec4f lo = extinction[i], hi = extinction[i + 1], base = extinctionIntegral[i];
    const Vec4f outside = x < 0.f ? extinction[0] : extinction[last];
    const float beyond = x - clamped;
    // Exact for the linear piece between entries i and i + 1.
    auto at = [&](float b, float l, float h, float o) { return b + f * l + g * (h - l) + beyond * o; };
    return {at(base.x, lo.x, hi.x, outside.x), at(base.y, lo.y, hi.y, outside.y),
            at(base.z, lo.z, hi.z, outside.z), at(base.w, lo.w, hi.w, outside.w)};
  }
};

/// Constant-time summaries of a transfer function's table over a scalar range, from prefix sums and a sparse
/// table of opacity maxima; the partitions' metadata is built from them on the host and on the GPU alike.
struct TransferFunctionRangeView {
  TransferFunctionView function;
  const double *prefixSum = nullptr;     ///< 4 per entry plus 4 leading zeros: running sums of r, g, b, a
  const double *prefixSquares = nullptr; ///< likewise, of their squares
  const float *opacityMax = nullptr; ///< level k (at k * size) holds the maximum over entries [i, i + 2^k)
  /// What the partitions' colour variances are normalised by, where given (TransferFunction::
  /// setVarianceRange); NaN: their own extremes.
  float varianceLowest = NAN, varianceHighest = NAN;

  /// Highest opacity the function takes over [a, b]; never below the true maximum; 0 for an empty range.
  UVR_HOST_DEVICE float maxOpacity(float a, float b) const {
    if (!(a <= b))
      return 0.f; // no finite value in the range
    int first, last;
    entryRange(a, b, first, last);
    const int level = floorLog2(unsigned(last - first + 1)); // two runs of 2^level entries cover the range
    const float *maxima = opacityMax + size_t(level) * size_t(function.size);
    return maxf(maxima[first], maxima[last + 1 - (1 << level)]);
  }

  /// Variance of colour and opacity (summed over r, g, b, a) over [a, b].
  UVR_HOST_DEVICE float colorVariance(float a, float b) const {
    if (!(a <= b))
      return 0.f;
    int first, last;
    entryRange(a, b, first, last);
    const double n = double(last - first + 1);
    double variance = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double sum = prefixSum[4 * (last + 1) + k] - prefixSum[4 * first + k];
      const double squares = prefixSquares[4 * (last + 1) + k] - prefixSquares[4 * first + k];
      const double v = squares / n - (sum / n) * (sum / n);
      variance += v > 0.0 ? v : 0.0;
    }
    return float(variance);
  }

private:
  UVR_HOST_DEVICE static int floorLog2(unsigned n) {
#if defined(__CUDA_ARCH__)
    return 31 - __clz(int(n));
#else
    return 31 - __builtin_clz(n);
#endif
  }
  /// The table entries whose linear pieces reach into [a, b].
  UVR_HOST_DEVICE void entryRange(float a, float b, int &first, int &last) const {
    const float lastEntry = float(function.size - 1);
    first = int(floorf(clampf((a - function.valueMin) * function.scale, 0.f, lastEntry)));
    last = int(ceilf(clampf((b - function.valueMin) * function.scale, 0.f, lastEntry)));
  }
};

/// A colour map stretched over [valueMin, valueMax] and sampled into a table.
class TransferFunction {
public:
  static constexpr int kDefaultTableSize = 1024;

  TransferFunction(const ColorMap &map, float valueMin, float valueMax, int tableSize = kDefaultTableSize);

  TransferFunctionView view() const;
  TransferFunctionRangeView rangeView() const;
  float valueMin() const { return valueMin_; }
  float valueMax() const { return valueMax_; }
  const std::vector<Vec4f> &table() const { return table_; }
  const std::vector<double> &prefixSums() const { return prefixSum_; }
  const std::vector<double> &prefixSquares() const { return prefixSquares_; }
  const std::vector<float> &opacityMaxima() const { return opacityMax_; }
  const std::vector<Vec4f> &extinction() const { return extinction_; }
  const std::vector<Vec4f> &extinctionIntegral() const { return extinctionIntegral_; }

  float maxOpacity(float a, float b) const { return rangeView().maxOpacity(a, b); }
  float colorVariance(float a, float b) const { return rangeView().colorVariance(a, b); }

  /// Normalises the partitions' colour variances by [lowest, highest] rather than by their own extremes
  /// (NaN: their own): a piece of a mesh split among processes takes the whole mesh's, so that its adaptive
  /// steps are the whole mesh's.
  void setVarianceRange(float lowest, float highest) {
    varianceLowest_ = lowest;
    varianceHighest_ = highest;
  }

private:
  std::vector<Vec4f> table_;
  float valueMin_, valueMax_;
  std::vector<double> prefixSum_, prefixSquares_; ///< see TransferFunctionRangeView
  std::vector<float> opacityMax_;                 ///< levels of size() entries each, unused tails zero
  std::vector<Vec4f> extinction_;                 ///< see TransferFunctionView
  std::vector<Vec4f> extinctionIntegral_;
  float varianceLowest_ = NAN, varianceHighest_ = NAN;
};

/// nodeMinSigma's mark for a node with a transparent partition below.
constexpr float kTransparentSigma = -1.f;

/// What space skipping and adaptive sampling read per partition; recomputed on every transfer-function change
/// in time linear in table entries and partitions, independent of the cell count.
struct PartitionMetadata {
  std::vector<float> maxOpacity;
  std::vector<float> nodeMaxOpacity; ///< per KD node, the maximum over the partitions below
  std::vector<float> sigma;          ///< colour standard deviation, normalised over all partitions to [0, 1]
  /// Per KD node, the smallest sigma of the partitions below, or -1 where one of them is transparent: where
  /// it asks for the finest step, the integrator marches the node's partitions as one (traversePartitions).
  std::vector<float> nodeMinSigma;
  uint32_t transparentCount = 0;
  /// The extremes of the colour variances over the partitions drawn ({+inf, -inf} where none), whatever
  /// the normalisation took (TransferFunction::setVarianceRange).
  float varianceLowest = INFINITY, varianceHighest = -INFINITY;
};

/// On the host, with all cores; the CUDA backend computes the same on the GPU. With `iso`, a partition that
/// the function makes transparent but whose range holds an isosurface is marked kIsoVisitOpacity (marched,
/// not counted transparent, its steps as a drawn one's), and with iso->hideVolume the function counts as
/// transparent everywhere.
PartitionMetadata computePartitionMetadata(const Partitions &partitions, const TransferFunction &tf,
                                           const IsoSettings *iso = nullptr);

/// A partition's colour deviation normalised by the extremes of the variances over the partitions drawn
/// (paper §2.1): 1 when they are all alike, so that adaptive sampling then takes the finest step.
UVR_HOST_DEVICE inline float normalizedSigma(float variance, float lowest, float highest) {
  const float span = highest - lowest;
  return span > 0.f ? sqrtf(clampf((variance - lowest) / span, 0.f, 1.f)) : 1.f;
}

} // namespace uvr
