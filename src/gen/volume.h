// Structured scalar volumes (NIfTI-1 and raw files) that `uvr gen` meshes: values on a voxel grid, the map
// from voxel indices to world coordinates, trilinear sampling and a min/max pyramid for range queries.
#pragma once

#include "core/vec.h"

#include <uvr/gen.h>

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

/// NIfTI-1 single-file volume (.nii, or gzip-compressed .nii.gz): uint8, int8, int16, uint16, int32, uint32,
/// float32, float64 in either byte order; the sform when its code is set, else the qform, else pixdim.
Volume readNifti(const std::string &path);

/// Headerless little-endian volume of `dims` voxels of `type`, x fastest, with `spacing` between voxels.
Volume readRawVolume(const std::string &path, std::array<int64_t, 3> dims, VoxelType type,
                     std::array<double, 3> spacing);

/// Otsu's threshold over a 256-bin histogram of the values: the value that best splits them in two classes.
float otsuThreshold(const Volume &volume);

/// Minimum and maximum of the voxel values over boxes of voxels, answered from a pyramid of 2×2×2 blocks.
class RangePyramid {
public:
  explicit RangePyramid(const Volume &volume);
  /// Range of the voxels with indices in [lo, hi] (inclusive, clamped to the grid), or of a slightly larger
  /// box: the blocks that cover it reach up to a quarter of its size beyond each side.
  void range(std::array<int64_t, 3> lo, std::array<int64_t, 3> hi, float &min, float &max) const;

private:
  struct Level {
    std::array<int64_t, 3> dims;
    std::vector<float> min, max;
  };
  const Volume &volume_;
  std::vector<Level> levels_; ///< levels_[k] holds blocks of 2^(k+1) voxels per axis
};

} // namespace uvr
