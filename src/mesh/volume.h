// Structured scalar volumes: values on a voxel grid, the map from voxel indices to world coordinates and
// trilinear sampling. io reads them (NIfTI, raw files); `uvr gen` meshes them.
#pragma once

#include "core/vec.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace uvr {

/// Voxel values as floats (scl_slope / scl_inter applied), x fastest. `toWorld` maps continuous voxel
/// indices (i, j, k) to world coordinates: row r is (a, b, c, t) with world_r = a·i + b·j + c·k + t.
struct Volume {
  std::array<int64_t, 3> dims{0, 0, 0};
  std::vector<float> values;
  std::array<std::array<double, 4>, 3> toWorld{};
  std::string name; ///< the file's stem; names the sampled field

  uint64_t voxelCount() const { return uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]); }
  float at(int64_t i, int64_t j, int64_t k) const {
    return values[uint64_t(i) + uint64_t(dims[0]) * (uint64_t(j) + uint64_t(dims[1]) * uint64_t(k))];
  }
  /// Trilinear interpolation at continuous voxel indices, clamped to the grid.
  float sample(double i, double j, double k) const;
  Vec3f world(double i, double j, double k) const;
  /// Determinant of the linear part of toWorld: negative when the map mirrors.
  double worldDeterminant() const;
};

} // namespace uvr
