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

std::vector<double> selectRanks(uint64_t count, const std::vector<uint64_t> &ranks,
                                const std::function<double(uint64_t)> &value, uint64_t gatherAtMost) {
  constexpr int kDigitBits = 16;
  constexpr size_t kDigits = size_t(1) << kDigitBits;
  // Where each rank's search stands: the value at it has the digits `prefix` above bit `shift`, and is the
  // `rank`-th of the values that have them.
  struct Search {
    uint64_t rank, prefix = 0;
    int shift = 64;
    bool gather = false, done = false;
  };
  std::vector<Search> searches;
  for (const uint64_t rank : ranks)
    searches.push_back({rank});
  std::vector<double> found(ranks.size());
  // Searches that stand at the same digits share each pass: the values with them, counted or gathered.
  const auto groupsOf = [&](bool gather) {
    std::vector<std::pair<uint64_t, int>> groups;
    for (const Search &search : searches)
      if (!search.done && search.gather == gather &&
          std::find(groups.begin(), groups.end(), std::pair{search.prefix, search.shift}) == groups.end())
        groups.emplace_back(search.prefix, search.shift);
    return groups;
  };
  const auto groupOf = [](const std::vector<std::pair<uint64_t, int>> &groups, const Search &search) {
    return size_t(std::find(groups.begin(), groups.end(), std::pair{search.prefix, search.shift}) -
                  groups.begin());
  };
  const auto inGroup = [](uint64_t bits, const std::pair<uint64_t, int> &group) {
    return group.second == 64 || bits >> group.second == group.first;
  };
  for (;;) {
    // Of the values of each group's digits, how many have each next digit.
    const std::vector<std::pair<uint64_t, int>> counted = groupsOf(false);
    if (!counted.empty()) {
      tbb::combinable<std::vector<uint64_t>> counts(
          [&] { return std::vector<uint64_t>(counted.size() * kDigits, 0); });
      tbb::parallel_for(
          tbb::blocked_range<uint64_t>(0, count, 1 << 14), [&](const tbb::blocked_range<uint64_t> &r) {
            std::vector<uint64_t> &local = counts.local();
            for (uint64_t c = r.begin(); c < r.end(); ++c) {
              const uint64_t bits = orderedBits(value(c));
              for (size_t g = 0; g < counted.size(); ++g)
                if (inGroup(bits, counted[g]))
                  ++local[g * kDigits + ((bits >> (counted[g].second - kDigitBits)) & (kDigits - 1))];
            }
          });
      std::vector<uint64_t> total(counted.size() * kDigits, 0);
      counts.combine_each([&](const std::vector<uint64_t> &local) {
        for (size_t d = 0; d < total.size(); ++d)
          total[d] += local[d];
      });
      for (size_t i = 0; i < searches.size(); ++i) {
        Search &search = searches[i];
        if (search.done || search.gather)
          continue;
        const uint64_t *digits = total.data() + groupOf(counted, search) * kDigits;
        size_t digit = 0;
        while (search.rank >= digits[digit])
          search.rank -= digits[digit++];
        search.prefix = search.prefix << kDigitBits | digit;
        search.shift -= kDigitBits;
        if (search.shift == 0) {
          found[i] = fromOrderedBits(search.prefix);
          search.done = true;
        } else {
          search.gather = digits[digit] <= gatherAtMost; // few enough to select among
        }
      }
    }
    const std::vector<std::pair<uint64_t, int>> gathered = groupsOf(true);
    if (gathered.empty()) {
      if (counted.empty())
        return found;
      continue;
    }
    tbb::combinable<std::vector<std::vector<double>>> lists(
        [&] { return std::vector<std::vector<double>>(gathered.size()); });
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, 1 << 14),
                      [&](const tbb::blocked_range<uint64_t> &r) {
                        std::vector<std::vector<double>> &local = lists.local();
                        for (uint64_t c = r.begin(); c < r.end(); ++c) {
                          const double v = value(c);
                          const uint64_t bits = orderedBits(v);
                          for (size_t g = 0; g < gathered.size(); ++g)
                            if (inGroup(bits, gathered[g]))
                              local[g].push_back(v);
                        }
                      });
    std::vector<std::vector<double>> values(gathered.size());
    lists.combine_each([&](const std::vector<std::vector<double>> &local) {
      for (size_t g = 0; g < values.size(); ++g)
        values[g].insert(values[g].end(), local[g].begin(), local[g].end());
    });
    for (size_t i = 0; i < searches.size(); ++i) {
      Search &search = searches[i];
      if (search.done || !search.gather)
        continue;
      std::vector<double> &group = values[groupOf(gathered, search)];
      const auto at = group.begin() + std::ptrdiff_t(search.rank);
      std::nth_element(group.begin(), at, group.end());
      found[i] = *at;
      search.done = true;
    }
  }
}

double selectRank(uint64_t count, uint64_t rank, const std::function<double(uint64_t)> &value,
                  uint64_t gatherAtMost) {
  return selectRanks(count, {rank}, value, gatherAtMost)[0];
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
  const std::vector<double> at =
      selectRanks(count, {0, count / 100, count / 2, count - 1 - count / 100, count - 1}, volume);
  stats.min = at[0];
  stats.p1 = at[1];
  stats.median = at[2];
  stats.p99 = at[3];
  stats.max = at[4];
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
