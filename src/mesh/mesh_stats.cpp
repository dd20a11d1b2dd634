#include "mesh/mesh_stats.h"

#include "mesh/cell.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
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

VolumeStats volumeStats(const Mesh &mesh) {
  VolumeStats stats;
  const uint64_t count = mesh.cellCount();
  if (count == 0)
    return stats;
  const MeshView view = makeMeshView(mesh, -1);
  std::vector<double> volumes(count);
  tbb::parallel_for(uint64_t(0), count, [&](uint64_t c) { volumes[c] = cellVolume(view, c); });
  const auto [lo, hi] = std::minmax_element(volumes.begin(), volumes.end());
  stats.min = *lo;
  stats.max = *hi;
  auto at = [&](uint64_t rank) {
    auto it = volumes.begin() + std::ptrdiff_t(rank);
    std::nth_element(volumes.begin(), it, volumes.end());
    return *it;
  };
  stats.median = at(count / 2);
  stats.p1 = at(count / 100);
  stats.p99 = at(count - 1 - count / 100);
  stats.medianPerTet = stats.median;
  if (mesh.tetCount() != count) {
    tbb::parallel_for(uint64_t(0), count, [&](uint64_t c) {
      const CellType type = cellType(view, c);
      volumes[c] /= type == CellType::Hexahedron ? 6.0
                    : type == CellType::Wedge    ? 3.0
                    : type == CellType::Pyramid  ? 2.0
                                                 : 1.0;
    });
    stats.medianPerTet = at(count / 2);
  }
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
