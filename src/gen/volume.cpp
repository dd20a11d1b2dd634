#include "gen/volume.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>

namespace uvr {

namespace {

constexpr int kHeaderSize = 348;
// Whole volumes are held as floats: refuse headers that would ask for more than this many voxels.
constexpr uint64_t kMaxVoxels = uint64_t(1) << 34;

/// Reads exactly `size` bytes from the start of a file, through zlib (which passes plain files through).
class VolumeFile {
public:
  explicit VolumeFile(const std::string &path) : path_(path) {
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

private:
  std::string path_;
  gzFile file_;
  uint64_t offset_ = 0;
};

template <typename T> T loadScalar(const uint8_t *p, bool swap) {
  uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap)
    std::reverse(bytes, bytes + sizeof(T));
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

/// Reads `count` voxels of type T into floats, a slab at a time: memory grows with the data the file holds,
/// not with what its header claims (a gzipped file's length says nothing about its content).
template <typename T> std::vector<float> readVoxelsOf(VolumeFile &file, bool swap, uint64_t count) {
  constexpr uint64_t kSlabVoxels = uint64_t(1) << 24;
  std::vector<float> out;
  out.reserve(std::min(count, 4 * kSlabVoxels));
  std::vector<uint8_t> raw(std::min(count, kSlabVoxels) * sizeof(T));
  for (uint64_t done = 0; done < count;) {
    const uint64_t n = std::min(count - done, kSlabVoxels);
    file.read(raw.data(), n * sizeof(T), "voxel data");
    out.resize(done + n);
    float *slab = out.data() + done;
    tbb::parallel_for(uint64_t(0), n,
                      [&](uint64_t i) { slab[i] = float(loadScalar<T>(raw.data() + i * sizeof(T), swap)); });
    done += n;
  }
  return out;
}

/// Reads `count` voxels of NIfTI datatype `code` into floats.
std::vector<float> readVoxels(VolumeFile &file, int code, bool swap, uint64_t count,
                              const std::string &path) {
  switch (code) {
  case 2:
    return readVoxelsOf<uint8_t>(file, swap, count);
  case 256:
    return readVoxelsOf<int8_t>(file, swap, count);
  case 4:
    return readVoxelsOf<int16_t>(file, swap, count);
  case 512:
    return readVoxelsOf<uint16_t>(file, swap, count);
  case 8:
    return readVoxelsOf<int32_t>(file, swap, count);
  case 768:
    return readVoxelsOf<uint32_t>(file, swap, count);
  case 16:
    return readVoxelsOf<float>(file, swap, count);
  case 64:
    return readVoxelsOf<double>(file, swap, count);
  default:
    throw Error(
        path, "byte 70",
        "expected datatype uint8, int8, int16, uint16, int32, uint32, float32 or float64, found code " +
            std::to_string(code));
  }
}

std::string stemOf(const std::string &path) {
  std::string name = std::filesystem::path(path).filename().string();
  for (const char *suffix : {".gz", ".nii", ".raw"})
    if (name.size() > std::strlen(suffix) && name.ends_with(suffix))
      name.resize(name.size() - std::strlen(suffix));
  return name;
}

} // namespace

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

Volume readNifti(const std::string &path) {
  VolumeFile file(path);
  uint8_t header[kHeaderSize];
  file.read(header, kHeaderSize, "a 348-byte NIfTI-1 header");
  bool swap = false;
  if (loadScalar<int32_t>(header, false) != kHeaderSize) {
    swap = true;
    if (loadScalar<int32_t>(header, true) != kHeaderSize)
      throw Error(path, "byte 0", "expected sizeof_hdr 348 (a NIfTI-1 file)");
  }
  if (std::memcmp(header + 344, "n+1", 4) != 0)
    throw Error(path, "byte 344", "expected the single-file NIfTI-1 magic \"n+1\"");
  auto i16 = [&](int offset) { return loadScalar<int16_t>(header + offset, swap); };
  auto f32 = [&](int offset) { return loadScalar<float>(header + offset, swap); };

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
  if (volume.worldDeterminant() == 0.0)
    throw Error(path, "byte 76", "expected a non-singular voxel-to-world map (pixdim, qform or sform)");

  const float voxOffset = f32(108);
  if (!(voxOffset >= kHeaderSize) || voxOffset > float(1 << 30))
    throw Error(path, "byte 108", "expected vox_offset of at least 348");
  file.skip(uint64_t(voxOffset) - file.offset(), "header extensions");
  volume.values = readVoxels(file, i16(70), swap, volume.voxelCount(), path);

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
      throw Error(path, "", "expected positive --dims");
    if (!(spacing[a] > 0))
      throw Error(path, "", "expected positive --spacing");
    volume.toWorld[a][a] = spacing[a];
  }
  if (volume.voxelCount() > kMaxVoxels)
    throw Error(path, "", "volume too large");
  const int code = type == VoxelType::UInt8    ? 2
                   : type == VoxelType::Int16  ? 4
                   : type == VoxelType::UInt16 ? 512
                                               : 16;
  VolumeFile file(path);
  volume.values = readVoxels(file, code, false, volume.voxelCount(), path);
  return volume;
}

float otsuThreshold(const Volume &volume) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float v : volume.values)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (!(lo < hi))
    return lo <= hi ? lo : 0.f;
  constexpr int kBins = 256;
  std::vector<double> histogram(kBins, 0.0);
  const double scale = kBins / (double(hi) - lo);
  for (float v : volume.values)
    if (std::isfinite(v))
      histogram[std::min(kBins - 1, int((double(v) - lo) * scale))] += 1.0;
  double total = 0, sum = 0;
  for (int b = 0; b < kBins; ++b) {
    total += histogram[b];
    sum += b * histogram[b];
  }
  double weightBelow = 0, sumBelow = 0, best = -1;
  int bestBin = 0;
  for (int b = 0; b < kBins - 1; ++b) {
    weightBelow += histogram[b];
    sumBelow += b * histogram[b];
    const double weightAbove = total - weightBelow;
    if (weightBelow == 0 || weightAbove == 0)
      continue;
    const double meanBelow = sumBelow / weightBelow, meanAbove = (sum - sumBelow) / weightAbove;
    const double between = weightBelow * weightAbove * (meanBelow - meanAbove) * (meanBelow - meanAbove);
    if (between > best) {
      best = between;
      bestBin = b;
    }
  }
  // The split lies at the upper edge of the last bin of the lower class.
  return float(lo + (bestBin + 1) / scale);
}

RangePyramid::RangePyramid(const Volume &volume) : volume_(volume) {
  std::array<int64_t, 3> dims = volume.dims;
  const std::vector<float> *belowMin = &volume.values, *belowMax = &volume.values;
  while (dims[0] > 1 || dims[1] > 1 || dims[2] > 1) {
    Level level;
    for (int a = 0; a < 3; ++a)
      level.dims[a] = (dims[a] + 1) / 2;
    const uint64_t count = uint64_t(level.dims[0]) * uint64_t(level.dims[1]) * uint64_t(level.dims[2]);
    level.min.resize(count);
    level.max.resize(count);
    tbb::parallel_for(int64_t(0), level.dims[2], [&](int64_t k) {
      for (int64_t j = 0; j < level.dims[1]; ++j)
        for (int64_t i = 0; i < level.dims[0]; ++i) {
          float lo = std::numeric_limits<float>::infinity(), hi = -lo;
          for (int64_t z = 2 * k; z < std::min(2 * k + 2, dims[2]); ++z)
            for (int64_t y = 2 * j; y < std::min(2 * j + 2, dims[1]); ++y)
              for (int64_t x = 2 * i; x < std::min(2 * i + 2, dims[0]); ++x) {
                const uint64_t below =
                    uint64_t(x) + uint64_t(dims[0]) * (uint64_t(y) + uint64_t(dims[1]) * z);
                lo = minf(lo, (*belowMin)[below]);
                hi = maxf(hi, (*belowMax)[below]);
              }
          const uint64_t here =
              uint64_t(i) + uint64_t(level.dims[0]) * (uint64_t(j) + uint64_t(level.dims[1]) * k);
          level.min[here] = lo;
          level.max[here] = hi;
        }
    });
    levels_.push_back(std::move(level));
    belowMin = &levels_.back().min;
    belowMax = &levels_.back().max;
    dims = levels_.back().dims;
  }
}

void RangePyramid::range(std::array<int64_t, 3> lo, std::array<int64_t, 3> hi, float &min, float &max) const {
  int64_t extent = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::clamp<int64_t>(lo[a], 0, volume_.dims[a] - 1);
    hi[a] = std::clamp<int64_t>(hi[a], lo[a], volume_.dims[a] - 1);
    extent = std::max(extent, hi[a] - lo[a] + 1);
  }
  // Blocks of at most a quarter of the box: at most 6 per axis, reaching at most half the box beyond it.
  int level = -1;
  while (level + 1 < int(levels_.size()) && (int64_t(8) << (level + 1)) <= extent)
    ++level;
  min = std::numeric_limits<float>::infinity();
  max = -min;
  if (level < 0) {
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
      for (int64_t y = lo[1]; y <= hi[1]; ++y)
        for (int64_t x = lo[0]; x <= hi[0]; ++x) {
          const float v = volume_.at(x, y, z);
          min = minf(min, v);
          max = maxf(max, v);
        }
    return;
  }
  const Level &l = levels_[level];
  const int shift = level + 1;
  for (int64_t z = lo[2] >> shift; z <= hi[2] >> shift; ++z)
    for (int64_t y = lo[1] >> shift; y <= hi[1] >> shift; ++y)
      for (int64_t x = lo[0] >> shift; x <= hi[0] >> shift; ++x) {
        const uint64_t index = uint64_t(x) + uint64_t(l.dims[0]) * (uint64_t(y) + uint64_t(l.dims[1]) * z);
        min = minf(min, l.min[index]);
        max = maxf(max, l.max[index]);
      }
}

} // namespace uvr
