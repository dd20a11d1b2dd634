// NIfTI-1 and raw volume readers. Files are read through zlib, which passes plain files through, so a
// gzip-compressed .nii.gz reads as a .nii does.
#include "core/limits.h"
#include "io/file_buffer.h"
#include "io/scalar_type.h"
#include "io/volume_io.h"
#include <uvr/error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

namespace uvr {

namespace {

constexpr int kHeaderSize = 348;
// Whole volumes are held as floats: refuse headers that would ask for more than this many voxels.
constexpr uint64_t kMaxVoxels = uint64_t(1) << 34;

/// Reads exactly `size` bytes from the start of a file, through zlib (which passes plain files through).
class VolumeFile {
public:
  explicit VolumeFile(const std::string &path) : path_(path) {
    checkRegularFile(path); // gzopen would block on a FIFO
    std::error_code error;
    fileSize_ = std::filesystem::file_size(path, error);
    file_ = gzopen(path.c_str(), "rb");
    if (!file_)
      throw Error(path, "", "cannot open the file");
    gzbuffer(file_, 1 << 20);
  }
  ~VolumeFile() { gzclose(file_); }
  VolumeFile(const VolumeFile &) = delete;
  VolumeFile &operator=(const VolumeFile &) = delete;

  void read(void *out, uint64_t size, const char *what) {
    auto *bytes = static_cast<uint8_t *>(out);
    while (size > 0) {
      const unsigned chunk = unsigned(std::min<uint64_t>(size, 1u << 30));
      const int got = gzread(file_, bytes, chunk);
      if (got <= 0) {
        int code = 0;
        const char *message = gzerror(file_, &code);
        throw Error(path_, "byte " + std::to_string(offset_),
                    std::string("expected ") + what +
                        (code != Z_OK && code != Z_STREAM_END ? std::string(" (") + message + ")"
                                                              : std::string(", found the end of the file")));
      }
      bytes += got;
      size -= uint64_t(got);
      offset_ += uint64_t(got);
    }
  }
  void skip(uint64_t size, const char *what) {
    std::vector<uint8_t> scratch(std::min<uint64_t>(size, 1 << 16));
    while (size > 0) {
      const uint64_t chunk = std::min<uint64_t>(size, scratch.size());
      read(scratch.data(), chunk, what);
      size -= chunk;
    }
  }
  uint64_t offset() const { return offset_; }

  /// Fails before `bytes` more are read and `memory` bytes allocated for them unless the file can hold them:
  /// a plain file as they are, a gzipped one inflating at most kMaxDeflateRatio:1.
  void checkRoom(uint64_t bytes, uint64_t memory, const std::string &position) {
    const uint64_t ratio = gzdirect(file_) ? 1 : kMaxDeflateRatio;
    InflationBound(path_, fileSize_, ratio).claim(bytes, position, "the voxel data");
    checkMemoryLimit(path_, position, memory, "the volume's voxels as floats");
  }

private:
  std::string path_;
  uint64_t fileSize_ = 0;
  gzFile file_;
  uint64_t offset_ = 0;
};

/// The element type of NIfTI datatype `code`; throws for the codes not supported.
ScalarType niftiType(int code, const std::string &path) {
  switch (code) {
  case 2:
    return ScalarType::UInt8;
  case 256:
    return ScalarType::Int8;
  case 4:
    return ScalarType::Int16;
  case 512:
    return ScalarType::UInt16;
  case 8:
    return ScalarType::Int32;
  case 768:
    return ScalarType::UInt32;
  case 16:
    return ScalarType::Float32;
  case 64:
    return ScalarType::Float64;
  default:
    throw Error(
        path, "byte 70",
        "expected datatype uint8, int8, int16, uint16, int32, uint32, float32 or float64, found code " +
            std::to_string(code));
  }
}

/// Reads `count` voxels of `type` into floats, a slab at a time: memory grows with the data the file holds,
/// not with what its header claims (a gzipped file's length says nothing about its content).
std::vector<float> readVoxels(VolumeFile &file, ScalarType type, bool swap, uint64_t count) {
  constexpr uint64_t kSlabVoxels = uint64_t(1) << 24;
  const uint64_t size = scalarSize(type);
  std::vector<float> out;
  out.reserve(std::min(count, 4 * kSlabVoxels));
  std::vector<uint8_t> raw(std::min(count, kSlabVoxels) * size);
  for (uint64_t done = 0; done < count;) {
    const uint64_t n = std::min(count - done, kSlabVoxels);
    file.read(raw.data(), n * size, "voxel data");
    out.resize(done + n);
    float *slab = out.data() + done;
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n), [&](const tbb::blocked_range<uint64_t> &r) {
      convertPacked(type, swap, raw.data() + r.begin() * size, r.size(), slab + r.begin());
    });
    done += n;
  }
  return out;
}

std::string stemOf(const std::string &path) {
  std::string name = std::filesystem::path(path).filename().string();
  for (const char *suffix : {".gz", ".nii", ".raw"})
    if (name.size() > std::strlen(suffix) && name.ends_with(suffix))
      name.resize(name.size() - std::strlen(suffix));
  return name;
}

} // namespace

Volume readNifti(const std::string &path) {
  VolumeFile file(path);
  uint8_t header[kHeaderSize];
  file.read(header, kHeaderSize, "a 348-byte NIfTI-1 header");
  bool swap = false;
  if (loadValue<int32_t>(header) != kHeaderSize) {
    swap = true;
    if (loadValue<int32_t>(header, true) != kHeaderSize)
      throw Error(path, "byte 0", "expected sizeof_hdr 348 (a NIfTI-1 file)");
  }
  if (std::memcmp(header + 344, "n+1", 4) != 0)
    throw Error(path, "byte 344", "expected the single-file NIfTI-1 magic \"n+1\"");
  auto i16 = [&](int offset) { return loadValue<int16_t>(header + offset, swap); };
  auto f32 = [&](int offset) { return loadValue<float>(header + offset, swap); };

  Volume volume;
  volume.name = stemOf(path);
  const int rank = i16(40);
  if (rank < 1 || rank > 7)
    throw Error(path, "byte 40", "expected dim[0] between 1 and 7, found " + std::to_string(rank));
  for (int a = 0; a < 3; ++a) {
    volume.dims[a] = a < rank ? i16(42 + 2 * a) : 1;
    if (volume.dims[a] < 1)
      throw Error(path, "byte " + std::to_string(42 + 2 * a), "expected a positive dimension");
  }
  for (int a = 3; a < rank; ++a)
    if (i16(42 + 2 * a) > 1)
      throw Error(path, "byte " + std::to_string(42 + 2 * a), "expected a single 3D volume (dim[4..] = 1)");
  if (volume.voxelCount() > kMaxVoxels)
    throw Error(path, "byte 42", "volume too large");

  float pixdim[4];
  for (int a = 0; a < 4; ++a)
    pixdim[a] = f32(76 + 4 * a);
  const int qformCode = i16(252), sformCode = i16(254);
  auto &m = volume.toWorld;
  if (sformCode > 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        m[r][c] = f32(280 + 16 * r + 4 * c);
  } else if (qformCode > 0) {
    // NIfTI-1 method 2: rotation from the quaternion (b, c, d), spacing from pixdim, qfac = pixdim[0].
    const double b = f32(256), c = f32(260), d = f32(264);
    const double a = std::sqrt(std::max(0.0, 1.0 - (b * b + c * c + d * d)));
    const double qfac = pixdim[0] < 0 ? -1.0 : 1.0;
    const double rotation[3][3] = {{a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
                                   {2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b)},
                                   {2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b}};
    const double scale[3] = {pixdim[1], pixdim[2], pixdim[3] * qfac};
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col)
        m[r][col] = rotation[r][col] * scale[col];
      m[r][3] = f32(268 + 4 * r);
    }
  } else { // method 1: spacing only
    for (int r = 0; r < 3; ++r)
      m[r][r] = pixdim[r + 1] > 0 ? pixdim[r + 1] : 1.0;
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c)
      if (!std::isfinite(m[r][c]))
        throw Error(path,
                    sformCode > 0   ? "byte 280"
                    : qformCode > 0 ? "byte 256"
                                    : "byte 76",
                    "expected a finite voxel-to-world map (pixdim, qform or sform)");
  if (volume.worldDeterminant() == 0.0)
    throw Error(path, "byte 76", "expected a non-singular voxel-to-world map (pixdim, qform or sform)");

  const float voxOffset = f32(108);
  if (!(voxOffset >= kHeaderSize) || voxOffset > float(1 << 30))
    throw Error(path, "byte 108", "expected vox_offset of at least 348");
  file.skip(uint64_t(voxOffset) - file.offset(), "header extensions");
  file.checkRoom(volume.voxelCount() * scalarSize(niftiType(i16(70), path)),
                 volume.voxelCount() * sizeof(float), "byte 42");
  volume.values = readVoxels(file, niftiType(i16(70), path), swap, volume.voxelCount());

  const float slope = f32(112), intercept = f32(116);
  if (slope != 0.f && std::isfinite(slope) && std::isfinite(intercept) && (slope != 1.f || intercept != 0.f))
    tbb::parallel_for(uint64_t(0), uint64_t(volume.values.size()),
                      [&](uint64_t i) { volume.values[i] = volume.values[i] * slope + intercept; });
  return volume;
}

Volume readRawVolume(const std::string &path, std::array<int64_t, 3> dims, VoxelType type,
                     std::array<double, 3> spacing) {
  Volume volume;
  volume.name = stemOf(path);
  volume.dims = dims;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1)
      throw Error(path, "", "expected a positive voxel count on every axis");
    if (!(spacing[a] > 0) || !std::isfinite(spacing[a]))
      throw Error(path, "", "expected a positive, finite voxel spacing on every axis");
    volume.toWorld[a][a] = spacing[a];
  }
  if (volume.voxelCount() > kMaxVoxels)
    throw Error(path, "", "volume too large");
  const ScalarType scalar = type == VoxelType::UInt8    ? ScalarType::UInt8
                            : type == VoxelType::Int16  ? ScalarType::Int16
                            : type == VoxelType::UInt16 ? ScalarType::UInt16
                                                        : ScalarType::Float32;
  VolumeFile file(path);
  file.checkRoom(volume.voxelCount() * scalarSize(scalar), volume.voxelCount() * sizeof(float), "");
  volume.values = readVoxels(file, scalar, false, volume.voxelCount());
  return volume;
}

} // namespace uvr
