#include "mesh/mesh_stats.h"

#include "mesh/cell.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace uvr {

namespace {
double tetVolume(Vec3f a, Vec3f b, Vec3f c, Vec3f d) { return std::fabs(double(det3(b - a, c - a, d - a))) / 6.0; }
} // namespace

double cellVolume(const MeshView &mesh, uint64_t cell) {
  Vec3f p[8];
  int n = 0;
  forEachCellVertex(mesh, cell, [&](uint32_t v) { p[n++] = mesh.points[v]; });
  switch (n) {
  case 4:
    return tetVolume(p[0], p[1], p[2], p[3]);
  case 5: // pyramid: two tets over the base diagonal
    return tetVolume(p[0], p[1], p[2], p[4]) + tetVolume(p[0], p[2], p[3], p[4]);
  case 6: // wedge: three tets
    return tetVolume(p[0], p[1], p[2], p[3]) + tetVolume(p[1], p[2], p[3], p[4]) +
           tetVolume(p[2], p[3], p[4], p[5]);
  default: // hexahedron: five tets
    return tetVolume(p[0], p[1], p[3], p[4]) + tetVolume(p[1], p[2], p[3], p[6]) +
           tetVolume(p[1], p[4], p[5], p[6]) + tetVolume(p[3], p[4], p[6], p[7]) +
           tetVolume(p[1], p[3], p[4], p[6]);
  }
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
  auto middle = volumes.begin() + std::ptrdiff_t(count / 2);
  std::nth_element(volumes.begin(), middle, volumes.end());
  stats.median = *middle;
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

float defaultStepSize(const VolumeStats &volumes) { return float(std::cbrt(volumes.median)); }

} // namespace uvr
