#include "mesh/volume.h"

#include <algorithm>
#include <cstdint>

namespace uvr {

float Volume::sample(double i, double j, double k) const {
  const double p[3] = {i, j, k};
  int64_t base[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    const double c = std::clamp(p[a], 0.0, double(dims[a] - 1));
    base[a] = std::min<int64_t>(int64_t(c), std::max<int64_t>(dims[a] - 2, 0));
    t[a] = c - double(base[a]);
  }
  const int64_t step[3] = {dims[0] > 1 ? 1 : 0, dims[1] > 1 ? 1 : 0, dims[2] > 1 ? 1 : 0};
  double value = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    const double w = (dx ? t[0] : 1 - t[0]) * (dy ? t[1] : 1 - t[1]) * (dz ? t[2] : 1 - t[2]);
    value += w * at(base[0] + dx * step[0], base[1] + dy * step[1], base[2] + dz * step[2]);
  }
  return float(value);
}

Vec3f Volume::world(double i, double j, double k) const {
  Vec3f p;
  for (int r = 0; r < 3; ++r)
    p[r] = float(toWorld[r][0] * i + toWorld[r][1] * j + toWorld[r][2] * k + toWorld[r][3]);
  return p;
}

double Volume::worldDeterminant() const {
  const auto &m = toWorld;
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

} // namespace uvr
