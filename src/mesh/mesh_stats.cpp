#include "mesh/mesh_stats.h"

#include "mesh/cell.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>
#include <vector>

namespace uvr {

namespace {

double tetVolume(Vec3f a, Vec3f b, Vec3f c, Vec3f d) {
  return std::fabs(double(det3(b - a, c - a, d - a))) / 6.0;
}

/// Integral of |det J| by a quadrature rule exact for the trilinear hexahedron and the linear wedge.
template <int N>
double isoparametricVolume(const MeshView &mesh, uint64_t cell, const Vec3f *nodes, const double *weights,
                           int count) {
  Vec3f corner[N];
  int n = 0;
  forEachCellVertex(mesh, cell, [&](uint32_t v) { corner[n++] = mesh.points[v]; });
  double volume = 0.0;
  for (int q = 0; q < count; ++q) {
    ShapeFunctions<N> s;
    evaluateShape(nodes[q], s);
    Vec3f dr{}, ds{}, dt{};
    for (int i = 0; i < N; ++i) {
      dr = dr + corner[i] * s.derivative[i].x;
      ds = ds + corner[i] * s.derivative[i].y;
      dt = dt + corner[i] * s.derivative[i].z;
    }
    volume += weights[q] * std::fabs(double(det3(dr, ds, dt)));
  }
  return volume;
}

} // namespace

double cellVolume(const MeshView &mesh, uint64_t cell) {
  const float lo = float(0.5 - 0.5 / std::sqrt(3.0)), hi = float(0.5 + 0.5 / std::sqrt(3.0));
  switch (cellType(mesh, cell)) {
  case CellType::Tetra: {
    const uint32_t *v = mesh.tets + 4 * cell;
    return tetVolume(mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]);
  }
  case CellType::Pyramid: { // two tets over the base diagonal
    const uint32_t *v = mesh.pyramids + 5 * (cell - mesh.tetCount);
    const Vec3f *p = mesh.points;
    return tetVolume(p[v[0]], p[v[1]], p[v[2]], p[v[4]]) + tetVolume(p[v[0]], p[v[2]], p[v[3]], p[v[4]]);
  }
  case CellType::Wedge: { // 3-point triangle rule times 2-point Gauss
    const Vec3f nodes[6] = {{1 / 6.f, 1 / 6.f, lo}, {2 / 3.f, 1 / 6.f, lo}, {1 / 6.f, 2 / 3.f, lo},
                            {1 / 6.f, 1 / 6.f, hi}, {2 / 3.f, 1 / 6.f, hi}, {1 / 6.f, 2 / 3.f, hi}};
    const double weights[6] = {1 / 12.0, 1 / 12.0, 1 / 12.0, 1 / 12.0, 1 / 12.0, 1 / 12.0};
    return isoparametricVolume<6>(mesh, cell, nodes, weights, 6);
  }
  case CellType::Hexahedron: { // 2x2x2 Gauss
    Vec3f nodes[8];
    double weights[8];
    for (int q = 0; q < 8; ++q) {
      nodes[q] = {q & 1 ? hi : lo, q & 2 ? hi : lo, q & 4 ? hi : lo};
      weights[q] = 1 / 8.0;
    }
    return isoparametricVolume<8>(mesh, cell, nodes, weights, 8);
  }
  }
  return 0.0;
}

namespace {

/// Doubles as unsigned integers of the same order.
uint64_t orderedBits(double v) {
  const uint64_t u = std::bit_cast<uint64_t>(v);
  return u >> 63 ? ~u : u | (uint64_t(1) << 63);
}

double fromOrderedBits(uint64_t u) { return std::bit_cast<double>(u >> 63 ? u & ~(uint64_t(1) << 63) : ~u); }

} // namespace

double selectRank(uint64_t count, uint64_t rank, const std::function<double(uint64_t)> &value,
                  uint64_t gatherAtMost) {
  constexpr int kDigitBits = 16;
  constexpr size_t kDigits = size_t(1) << kDigitBits;
  uint64_t prefix = 0; // the digits found so far, of the value at `rank`
  for (int shift = 64 - kDigitBits;; shift -= kDigitBits) {
    // Of the values whose higher digits are the prefix, how many have each next digit.
    auto inPrefix = [&](uint64_t bits) {
      return shift + kDigitBits == 64 || bits >> (shift + kDigitBits) == prefix;
    };
    tbb::combinable<std::vector<uint64_t>> counts([] { return std::vector<uint64_t>(kDigits, 0); });
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, 1 << 14),
                      [&](const tbb::blocked_range<uint64_t> &r) {
                        std::vector<uint64_t> &local = counts.local();
                        for (uint64_t c = r.begin(); c < r.end(); ++c)
                          if (const uint64_t bits = orderedBits(value(c)); inPrefix(bits))
                            ++local[(bits >> shift) & (kDigits - 1)];
                      });
    std::vector<uint64_t> total(kDigits, 0);
    counts.combine_each([&](const std::vector<uint64_t> &local) {
      for (size_t d = 0; d < kDigits; ++d)
        total[d] += local[d];
    });
    size_t digit = 0;
    while (rank >= total[digit])
      rank -= total[digit++];
    prefix = prefix << kDigitBits | digit;
    if (shift == 0)
      return fromOrderedBits(prefix);
    if (total[digit] > gatherAtMost)
      continue;
    // Few enough: gather them and select among them.
    tbb::combinable<std::vector<double>> gathered;
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, 1 << 14),
                      [&](const tbb::blocked_range<uint64_t> &r) {
                        std::vector<double> &local = gathered.local();
                        for (uint64_t c = r.begin(); c < r.end(); ++c)
                          if (const double v = value(c); orderedBits(v) >> shift == prefix)
                            local.push_back(v);
                      });
    std::vector<double> values;
    values.reserve(total[digit]);
    gathered.combine_each(
        [&](const std::vector<double> &local) { values.insert(values.end(), local.begin(), local.end()); });
    auto it = values.begin() + std::ptrdiff_t(rank);
    std::nth_element(values.begin(), it, values.end());
    return *it;
  }
}

VolumeStats volumeStats(const Mesh &mesh) {
  VolumeStats stats;
  const uint64_t count = mesh.cellCount();
  if (count == 0)
    return stats;
  const MeshView view = makeMeshView(mesh, -1);
  // Selected by a radix select that computes the volumes again on each pass rather than keeping them (8
  // bytes a cell).
  auto volume = [&](uint64_t c) { return cellVolume(view, c); };
  using Extremes = std::pair<double, double>;
  const Extremes extremes = tbb::parallel_reduce(
      tbb::blocked_range<uint64_t>(0, count, 1 << 14), Extremes{INFINITY, -INFINITY},
      [&](const tbb::blocked_range<uint64_t> &r, Extremes e) {
        for (uint64_t c = r.begin(); c < r.end(); ++c) {
          const double v = volume(c);
          e = {std::min(e.first, v), std::max(e.second, v)};
        }
        return e;
      },
      [](Extremes a, Extremes b) {
        return Extremes{std::min(a.first, b.first), std::max(a.second, b.second)};
      });
  stats.min = extremes.first;
  stats.max = extremes.second;
  stats.median = selectRank(count, count / 2, volume);
  stats.p1 = selectRank(count, count / 100, volume);
  stats.p99 = selectRank(count, count - 1 - count / 100, volume);
  stats.medianPerTet = stats.median;
  if (mesh.tetCount() != count)
    stats.medianPerTet = selectRank(count, count / 2, [&](uint64_t c) {
      const CellType type = cellType(view, c);
      return volume(c) / (type == CellType::Hexahedron ? 6.0
                          : type == CellType::Wedge    ? 3.0
                          : type == CellType::Pyramid  ? 2.0
                                                       : 1.0);
    });
  return stats;
}

ValueRange valueRange(const ScalarField &field) {
  float lo = INFINITY, hi = -INFINITY;
  for (float v : field.values)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  return lo <= hi ? ValueRange{lo, hi} : ValueRange{};
}

float defaultStepSize(const VolumeStats &volumes, const Box3f &bounds) {
  if (!(bounds.lower.x <= bounds.upper.x))
    return 0.f;
  const Vec3f extent = bounds.upper - bounds.lower;
  const double diagonal = double(length(extent));
  const double thinnest = std::min({extent.x, extent.y, extent.z});
  const double step = std::cbrt(volumes.medianPerTet);
  return float(std::max(std::min(step, 0.25 * thinnest), 1e-4 * diagonal));
}

} // namespace uvr
