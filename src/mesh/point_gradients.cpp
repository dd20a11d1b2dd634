#include "mesh/point_gradients.h"

#include "mesh/cell.h"

#include <cmath>

namespace uvr {

namespace {

/// The vector g with dot(a, g) = da, dot(b, g) = db, dot(c, g) = dc (by Cramer's rule), and |det(a, b, c)|;
/// false where a, b and c are coplanar.
bool solveGradient(Vec3f a, Vec3f b, Vec3f c, float da, float db, float dc, Vec3f &g, float &volume) {
  const float det = det3(a, b, c);
  if (!(det != 0.f) || !std::isfinite(det))
    return false;
  g = (cross(b, c) * da + cross(c, a) * db + cross(a, b) * dc) * (1.f / det);
  volume = std::fabs(det);
  return true;
}

/// The gradient of the field `value` (per point) in cell `cell` of `n` corners `v`, and the cell's volume
/// (for other cells than tets, as the Jacobian at the centre gives it); false for a flat cell.
template <int N>
bool isoparametricGradient(const MeshView &mesh, const uint32_t *v, const float *value, Vec3f centre,
                           float referenceVolume, Vec3f &g, float &volume) {
  ShapeFunctions<N> s;
  evaluateShape(centre, s);
  Vec3f dr{}, ds{}, dt{};
  float fr = 0.f, fs = 0.f, ft = 0.f;
  for (int i = 0; i < N; ++i) {
    const Vec3f p = mesh.points[v[i]];
    dr = dr + p * s.derivative[i].x;
    ds = ds + p * s.derivative[i].y;
    dt = dt + p * s.derivative[i].z;
    fr += value[v[i]] * s.derivative[i].x;
    fs += value[v[i]] * s.derivative[i].y;
    ft += value[v[i]] * s.derivative[i].z;
  }
  // The chain rule: (fr, fs, ft) = J^T g, J's columns being dx/dr, dx/ds, dx/dt.
  if (!solveGradient(dr, ds, dt, fr, fs, ft, g, volume))
    return false;
  volume *= referenceVolume;
  return true;
}

bool cellGradient(const MeshView &mesh, uint64_t cell, const float *value, Vec3f &g, float &volume) {
  int n;
  const uint32_t *v = cellCorners(mesh, cell, n);
  switch (n) {
  case 4: {
    const Vec3f a = mesh.points[v[0]];
    const float fa = value[v[0]];
    if (!solveGradient(mesh.points[v[1]] - a, mesh.points[v[2]] - a, mesh.points[v[3]] - a, value[v[1]] - fa,
                       value[v[2]] - fa, value[v[3]] - fa, g, volume))
      return false;
    volume /= 6.f;
    return true;
  }
  case 5: // VTK's parametric centres, and the reference cells' volumes
    return isoparametricGradient<5>(mesh, v, value, {0.5f, 0.5f, 0.2f}, 1.f / 3.f, g, volume);
  case 6:
    return isoparametricGradient<6>(mesh, v, value, {1.f / 3.f, 1.f / 3.f, 0.5f}, 0.5f, g, volume);
  default:
    return isoparametricGradient<8>(mesh, v, value, {0.5f, 0.5f, 0.5f}, 1.f, g, volume);
  }
}

/// A cell's volume, for averaging cell data to the points: that of its gradient's solve, with a field of 0.
float cellVolume(const MeshView &mesh, uint64_t cell, const std::vector<float> &zeros) {
  Vec3f g;
  float volume = 0.f;
  return cellGradient(mesh, cell, zeros.data(), g, volume) ? volume : 0.f;
}

} // namespace

std::vector<Vec3f> computePointGradients(const MeshView &view, uint64_t pointCount) {
  std::vector<Vec3f> gradients(pointCount, Vec3f{});
  if (!view.values)
    return gradients;
  const uint64_t cells = view.cellCount();
  std::vector<float> pointValues;
  const float *values = view.values;
  if (view.cellCentered) {
    const std::vector<float> zeros(pointCount, 0.f);
    std::vector<double> sum(pointCount, 0.0), weight(pointCount, 0.0);
    for (uint64_t c = 0; c < cells; ++c) {
      const double volume = cellVolume(view, c, zeros);
      forEachCellVertex(view, c, [&](uint32_t p) {
        sum[p] += volume * double(view.values[c]);
        weight[p] += volume;
      });
    }
    pointValues.resize(pointCount);
    for (uint64_t p = 0; p < pointCount; ++p)
      pointValues[p] = weight[p] > 0.0 ? float(sum[p] / weight[p]) : 0.f;
    values = pointValues.data();
  }
  std::vector<double> weight(pointCount, 0.0);
  std::vector<double> sum(3 * pointCount, 0.0);
  for (uint64_t c = 0; c < cells; ++c) {
    Vec3f g;
    float volume;
    if (!cellGradient(view, c, values, g, volume) || !std::isfinite(g.x + g.y + g.z))
      continue;
    forEachCellVertex(view, c, [&](uint32_t p) {
      sum[3 * uint64_t(p) + 0] += double(volume) * double(g.x);
      sum[3 * uint64_t(p) + 1] += double(volume) * double(g.y);
      sum[3 * uint64_t(p) + 2] += double(volume) * double(g.z);
      weight[p] += volume;
    });
  }
  for (uint64_t p = 0; p < pointCount; ++p)
    if (weight[p] > 0.0)
      gradients[p] = {float(sum[3 * p] / weight[p]), float(sum[3 * p + 1] / weight[p]),
                      float(sum[3 * p + 2] / weight[p])};
  return gradients;
}

} // namespace uvr
