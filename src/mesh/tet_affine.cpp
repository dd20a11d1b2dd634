#include "mesh/tet_affine.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace uvr {

std::vector<TetAffine> buildTetAffine(const MeshView &mesh) {
  std::vector<TetAffine> records(mesh.tetCount);
  tbb::parallel_for(
      tbb::blocked_range<uint64_t>(0, mesh.tetCount), [&](const tbb::blocked_range<uint64_t> &r) {
        for (uint64_t t = r.begin(); t < r.end(); ++t) {
          const uint32_t *v = mesh.tets + 4 * t;
          const Vec3f a = mesh.points[v[0]];
          const Vec3f e1 = mesh.points[v[1]] - a, e2 = mesh.points[v[2]] - a, e3 = mesh.points[v[3]] - a;
          // As in tetBarycentricsAlong: the rows of the inverse of [e1 e2 e3].
          const Vec3f g1 = cross(e2, e3), g2 = cross(e3, e1), g3 = cross(e1, e2);
          const float volume = dot(e1, g1);
          const float inverse = volume != 0.f ? 1.f / volume : NAN;
          Vec3f weightGradient[3] = {g1 * inverse, g2 * inverse, g3 * inverse}, valueGradient{};
          TetAffine &record = records[t];
          record.corner = a;
          if (mesh.cellCentered) {
            record.valueAtCorner = mesh.values[t];
          } else {
            const float f0 = mesh.values[v[0]];
            record.valueAtCorner = f0;
            valueGradient = weightGradient[0] * (mesh.values[v[1]] - f0) +
                            weightGradient[1] * (mesh.values[v[2]] - f0) +
                            weightGradient[2] * (mesh.values[v[3]] - f0);
          }
          for (int i = 0; i < 4; ++i) {
            const Vec3f g = i < 3 ? weightGradient[i] : valueGradient;
            record.gradientX[i] = g.x;
            record.gradientY[i] = g.y;
            record.gradientZ[i] = g.z;
          }
        }
      });
  return records;
}

} // namespace uvr
