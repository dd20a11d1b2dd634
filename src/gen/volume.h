// What `uvr gen` asks of a volume beyond its values: Otsu's threshold and a min/max pyramid for range
// queries.
#pragma once

#include "mesh/volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace uvr {

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
