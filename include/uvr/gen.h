// Unstructured meshes made from structured scalar volumes (what `uvr gen` does): graded, conforming
// tetrahedra or hexahedra over the region where the volume passes a threshold, the volume sampled at the
// vertices as a point field named after the volume.
#pragma once

#include <uvr/mesh.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace uvr {

/// Element types of raw volumes (NIfTI files name theirs in the header).
enum class VoxelType : uint8_t { UInt8, Int16, UInt16, Float32 };

struct GenOptions {
  uint64_t cells = 1000000;       ///< target cell count; the result lands within ±10 %
  std::optional<float> threshold; ///< keep cells whose centroid value is ≥ this; default: Otsu's threshold
  uint64_t seed = 0;              ///< seeds the jitter of the vertices
  bool cellField = false;         ///< also store the value at each cell's centroid, as "<name>_cell"
};

/// A structured scalar volume: voxel values as floats on a grid placed in world coordinates. Shared and
/// unchanging, as VolumeMesh.
class VoxelVolume {
public:
  /// NIfTI-1 single-file volume (.nii, or gzip-compressed .nii.gz): uint8, int8, int16, uint16, int32,
  /// uint32, float32, float64 in either byte order; the sform when its code is set, else the qform, else
  /// pixdim. Throws uvr::Error naming the file.
  static VoxelVolume readNifti(const std::string &path);
  /// Headerless little-endian volume of `dims` voxels of `type`, x fastest, with `spacing` between voxels.
  static VoxelVolume readRaw(const std::string &path, std::array<int64_t, 3> dims, VoxelType type,
                             std::array<double, 3> spacing);

  /// The file's stem: names the sampled field.
  const std::string &name() const;
  std::array<int64_t, 3> dims() const;

  /// The threshold a mesh of `options` keeps cells by: the option's, else Otsu's threshold of the volume's
  /// 256-bin histogram.
  float threshold(const GenOptions &options) const;
  /// Meshes the volume with cells of `type` (CellType::Tetra or CellType::Hexahedron). The same inputs and
  /// seed give the same mesh on any number of threads.
  VolumeMesh generateMesh(const GenOptions &options, CellType type = CellType::Tetra) const;

private:
  struct Impl;
  explicit VoxelVolume(std::shared_ptr<const Impl> impl);
  std::shared_ptr<const Impl> impl_;
};

} // namespace uvr
