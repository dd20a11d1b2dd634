#include "gen/mesher.h"

#include <tbb/parallel_for.h>

namespace uvr {

ScalarField sampleCellCentroids(const Volume &volume, const Mesh &mesh) {
  // Back from world to voxel indices through the inverse of toWorld's linear part.
  const auto &m = volume.toWorld;
  const double det = volume.worldDeterminant();
  double inverse[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
      inverse[r][c] = (m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]) / det;
    }
  ScalarField field{volume.name + "_cell", Centering::Cell, UninitVector<float>(mesh.cellCount(), 0.f)};
  auto sampleAt = [&](const uint32_t *corners, int count) {
    double centroid[3] = {0, 0, 0};
    for (int k = 0; k < count; ++k) {
      const Vec3f p = mesh.points[corners[k]];
      for (int a = 0; a < 3; ++a)
        centroid[a] += double(p[a]) / count;
    }
    double local[3] = {centroid[0] - m[0][3], centroid[1] - m[1][3], centroid[2] - m[2][3]};
    double index[3];
    for (int r = 0; r < 3; ++r)
      index[r] = inverse[r][0] * local[0] + inverse[r][1] * local[1] + inverse[r][2] * local[2];
    return volume.sample(index[0], index[1], index[2]);
  };
  const uint64_t tets = mesh.tetCount(), hexes = mesh.hexCount();
  tbb::parallel_for(uint64_t(0), tets, [&](uint64_t t) { field.values[t] = sampleAt(&mesh.tets[4 * t], 4); });
  // Cells are numbered tets, pyramids, wedges, hexahedra; the generators make no pyramids or wedges.
  tbb::parallel_for(uint64_t(0), hexes,
                    [&](uint64_t h) { field.values[tets + h] = sampleAt(&mesh.hexes[8 * h], 8); });
  return field;
}

} // namespace uvr
