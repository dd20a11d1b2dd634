// Image comparison: SSIM exactly as scikit-image computes it (so numbers can be compared with the paper's
// and with Python tooling), and PSNR.
#include <uvr/error.h>
#include <uvr/image.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace uvr {

namespace {

void checkComparable(const Image &a, const Image &b) {
  if (a.width != b.width || a.height != b.height)
    throw Error("cannot compare images of different sizes: " + std::to_string(a.width) + "x" +
                std::to_string(a.height) + " and " + std::to_string(b.width) + "x" +
                std::to_string(b.height));
  if (a.width <= 0 || a.height <= 0)
    throw Error("cannot compare empty images");
}

// scipy.ndimage sizes a Gaussian kernel as int(truncate * sigma + 0.5); skimage uses truncate = 3.5 and
// sigma = 1.5, giving radius 5, the 11x11 window of Wang et al. 2004.
constexpr double kSigma = 1.5;
constexpr int kRadius = 5;
constexpr int kTaps = 2 * kRadius + 1;
constexpr size_t kBlock = 256; ///< row elements filtered vertically at a time

using Kernel = std::array<double, kTaps>;

/// scipy.ndimage's 1D Gaussian kernel: exp(-x^2 / (2 sigma^2)) normalised to sum 1.
Kernel gaussianKernel() {
  Kernel weights;
  double sum = 0;
  for (int i = 0; i < kTaps; ++i) {
    const double x = i - kRadius;
    weights[i] = std::exp(-0.5 / (kSigma * kSigma) * x * x);
    sum += weights[i];
  }
  for (double &w : weights)
    w /= sum;
  return weights;
}

/// The five local moments SSIM needs: weighted means of a, b, a^2, b^2 and ab.
enum Moment { MeanA, MeanB, MeanAA, MeanBB, MeanAB, MomentCount };

/// Adds one tap of the vertical filter, weight w: w times rows a and b and their products. The restrict
/// qualifiers tell the compiler the outputs overlap nothing, which it needs to vectorise.
void accumulateMoments(const uint8_t *__restrict rowA, const uint8_t *__restrict rowB, double w, size_t n,
                       double *__restrict meanA, double *__restrict meanB, double *__restrict meanAA,
                       double *__restrict meanBB, double *__restrict meanAB) {
  for (size_t i = 0; i < n; ++i) {
    const double pa = rowA[i], pb = rowB[i];
    meanA[i] += w * pa;
    meanB[i] += w * pb;
    meanAA[i] += w * (pa * pa);
    meanBB[i] += w * (pb * pb);
    meanAB[i] += w * (pa * pb);
  }
}

/// The horizontal filter for output elements [first, last) of an interleaved RGB row.
void filterHorizontally(const double *__restrict in, double *__restrict out, size_t first, size_t last,
                        const Kernel &kernel) {
  for (size_t i = first; i < last; ++i) {
    double sum = kernel[kRadius] * in[i]; // the kernel is symmetric: pair the taps
    for (int d = 1; d <= kRadius; ++d)
      sum += kernel[kRadius + d] * (in[i - 3 * d] + in[i + 3 * d]);
    out[i] = sum;
  }
}

/// SSIM of row y summed per channel over the pixels skimage keeps (all but kRadius at either end).
/// `scratch` holds 2 * MomentCount + 1 rows of doubles.
std::array<double, 3> ssimRowSums(const Image &a, const Image &b, int y, const Kernel &kernel,
                                  std::vector<double> &scratch) {
  constexpr double c1 = (0.01 * 255) * (0.01 * 255);
  constexpr double c2 = (0.03 * 255) * (0.03 * 255);
  const size_t rowLength = size_t(a.width) * 3; // channels stay interleaved; horizontal taps are 3 apart
  const size_t first = kRadius * 3, last = rowLength - kRadius * 3;
  double *v[MomentCount], *u[MomentCount];
  for (int m = 0; m < MomentCount; ++m) {
    v[m] = scratch.data() + m * rowLength;
    u[m] = scratch.data() + (MomentCount + m) * rowLength;
  }
  double *similarity = scratch.data() + 2 * MomentCount * rowLength;

  // Separable filter, along y first as scipy does, over the whole row; in blocks, so that the sums being
  // accumulated stay in the L1 cache.
  std::fill(v[0], v[0] + MomentCount * rowLength, 0.0);
  for (size_t start = 0; start < rowLength; start += kBlock) {
    const size_t n = std::min(kBlock, rowLength - start);
    for (int k = 0; k < kTaps; ++k)
      accumulateMoments(a.pixel(0, y + k - kRadius) + start, b.pixel(0, y + k - kRadius) + start, kernel[k],
                        n, v[MeanA] + start, v[MeanB] + start, v[MeanAA] + start, v[MeanBB] + start,
                        v[MeanAB] + start);
  }
  // Then along x, only where the result is kept.
  for (int m = 0; m < MomentCount; ++m)
    filterHorizontally(v[m], u[m], first, last, kernel);

  for (size_t i = first; i < last; ++i) {
    const double ux = u[MeanA][i], uy = u[MeanB][i];
    const double vx = u[MeanAA][i] - ux * ux, vy = u[MeanBB][i] - uy * uy, vxy = u[MeanAB][i] - ux * uy;
    similarity[i] = ((2 * ux * uy + c1) * (2 * vxy + c2)) / ((ux * ux + uy * uy + c1) * (vx + vy + c2));
  }
  std::array<double, 3> sums{};
  for (size_t i = first; i < last; i += 3)
    for (int c = 0; c < 3; ++c)
      sums[c] += similarity[i + c];
  return sums;
}

} // namespace

double ssim(const Image &a, const Image &b) {
  checkComparable(a, b);
  const int width = a.width, height = a.height;
  if (width < kTaps || height < kTaps)
    throw Error("SSIM needs images of at least " + std::to_string(kTaps) + "x" + std::to_string(kTaps) +
                " pixels, got " + std::to_string(width) + "x" + std::to_string(height));

  // skimage filters whole images (mode 'reflect'), then crops a border of (win_size - 1) / 2 pixels before
  // averaging. That border equals the kernel radius, so every pixel that counts has its whole window
  // inside the image: only those are computed, and the boundary mode never matters.
  const Kernel kernel = gaussianKernel();
  std::vector<std::array<double, 3>> rowSums(size_t(height - 2 * kRadius));
  tbb::parallel_for(tbb::blocked_range<int>(kRadius, height - kRadius),
                    [&](const tbb::blocked_range<int> &rows) {
                      std::vector<double> scratch((2 * MomentCount + 1) * size_t(width) * 3);
                      for (int y = rows.begin(); y != rows.end(); ++y)
                        rowSums[size_t(y - kRadius)] = ssimRowSums(a, b, y, kernel, scratch);
                    });

  // Summing per row, then rows in order, keeps the result independent of the thread schedule.
  std::array<double, 3> channelSums{};
  for (const auto &sums : rowSums)
    for (int c = 0; c < 3; ++c)
      channelSums[c] += sums[c];
  const double count = double(width - 2 * kRadius) * double(height - 2 * kRadius);
  return (channelSums[0] / count + channelSums[1] / count + channelSums[2] / count) / 3;
}

double psnr(const Image &a, const Image &b) {
  checkComparable(a, b);
  uint64_t squaredError = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    const int d = int(a.rgb[i]) - int(b.rgb[i]);
    squaredError += uint64_t(d * d);
  }
  if (squaredError == 0)
    return std::numeric_limits<double>::infinity();
  const double mse = double(squaredError) / double(a.rgb.size());
  return 10 * std::log10(255.0 * 255.0 / mse);
}

} // namespace uvr
