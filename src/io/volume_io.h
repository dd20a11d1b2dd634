// Structured volume readers: NIfTI-1 and headerless raw files, read into a Volume.
#pragma once

#include "mesh/volume.h"

#include <uvr/gen.h>

#include <array>
#include <cstdint>
#include <string>

namespace uvr {

/// NIfTI-1 single-file volume (.nii, or gzip-compressed .nii.gz): uint8, int8, int16, uint16, int32, uint32,
/// float32, float64 in either byte order; the sform when its code is set, else the qform, else pixdim.
Volume readNifti(const std::string &path);

/// Headerless little-endian volume of `dims` voxels of `type`, x fastest, with `spacing` between voxels.
Volume readRawVolume(const std::string &path, std::array<int64_t, 3> dims, VoxelType type,
                     std::array<double, 3> spacing);

} // namespace uvr
