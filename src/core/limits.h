// Bounds on what input may make the library allocate: the memory limit (<uvr/system.h>), checked against what
// a file claims before anything is allocated for it.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace uvr {

/// zlib (and gzip) never inflate more than about 1032:1.
constexpr uint64_t kMaxDeflateRatio = 1032;

/// Throws uvr::Error (path, position) unless `bytes` of `what` fit in the memory limit.
void checkMemoryLimit(const std::string &path, const std::string &position, uint64_t bytes,
                      const std::string &what);

/// The decoded bytes one file's arrays claim, summed over them all: each claim must fit, with those before
/// it, in `maxRatio` times the file's size (what its compression allows) and, beyond the file's own size,
/// in the memory limit. Call claim before allocating for the array.
class InflationBound {
public:
  InflationBound(std::string path, uint64_t fileBytes, uint64_t maxRatio)
      : path_(std::move(path)), fileBytes_(fileBytes), maxRatio_(maxRatio) {}
  /// Throws uvr::Error naming the file and `position` when `bytes` more would pass either bound.
  void claim(uint64_t bytes, const std::string &position, const std::string &what);
  uint64_t claimed() const { return claimed_; }

private:
  std::string path_;
  uint64_t fileBytes_;
  uint64_t maxRatio_;
  uint64_t claimed_ = 0;
};

/// `text` as an error message quotes it: cut to `maxChars` with "..." and the full length when longer.
std::string quoteInput(std::string_view text, size_t maxChars = 80);

/// "N bytes" in a readable unit (e.g. "4.0 GiB"), for messages.
std::string byteText(uint64_t bytes);

} // namespace uvr
