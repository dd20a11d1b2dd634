#include "core/limits.h"

#include <uvr/error.h>
#include <uvr/system.h>

#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>

namespace uvr {

namespace {

constexpr uint64_t kDefaultMemoryLimit = uint64_t(4) << 30;

std::atomic<uint64_t> &limitSetting() {
  static std::atomic<uint64_t> limit{0}; // 0: the default
  return limit;
}

uint64_t defaultMemoryLimit() {
  // Read once: the environment is the process's, and a malformed value must not fail every later call.
  static const uint64_t value = [] {
    const char *text = std::getenv("UVR_MEMORY_LIMIT");
    if (!text || !*text)
      return kDefaultMemoryLimit;
    try {
      return parseByteSize(text);
    } catch (const Error &) {
      std::fprintf(stderr,
                   "uvr: ignoring UVR_MEMORY_LIMIT=%s: expected bytes, or a number with K, M, G or T\n",
                   quoteInput(text).c_str());
      return kDefaultMemoryLimit;
    }
  }();
  return value;
}

} // namespace

uint64_t parseByteSize(const std::string &text) {
  size_t i = 0;
  uint64_t value = 0;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
    if (__builtin_mul_overflow(value, uint64_t(10), &value) ||
        __builtin_add_overflow(value, uint64_t(text[i] - '0'), &value))
      throw Error("memory limit '" + quoteInput(text) + "' is too large");
    ++i;
  }
  int shift = 0;
  if (i + 1 == text.size()) {
    switch (std::toupper(static_cast<unsigned char>(text[i]))) {
    case 'K':
      shift = 10;
      break;
    case 'M':
      shift = 20;
      break;
    case 'G':
      shift = 30;
      break;
    case 'T':
      shift = 40;
      break;
    default:
      shift = -1;
    }
    ++i;
  }
  if (i == 0 || i != text.size() || shift < 0 || value == 0)
    throw Error("memory limit '" + quoteInput(text) +
                "' is malformed: expected a positive number of bytes, optionally with K, M, G or T");
  if (shift > 0 && value > (UINT64_MAX >> shift))
    throw Error("memory limit '" + quoteInput(text) + "' is too large");
  return value << shift;
}

uint64_t memoryLimit() {
  const uint64_t set = limitSetting().load(std::memory_order_relaxed);
  return set ? set : defaultMemoryLimit();
}

void setMemoryLimit(uint64_t bytes) { limitSetting().store(bytes, std::memory_order_relaxed); }

std::string byteText(uint64_t bytes) {
  const char *units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  if (bytes < 1024)
    return std::to_string(bytes) + " bytes";
  double value = double(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 6) {
    value /= 1024.0;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.1f %s", value, units[unit]);
  return text;
}

void checkMemoryLimit(const std::string &path, const std::string &position, uint64_t bytes,
                      const std::string &what) {
  const uint64_t limit = memoryLimit();
  if (bytes > limit)
    throw Error(path, position,
                what + " needs " + byteText(bytes) + ", over the memory limit of " + byteText(limit) +
                    " (raise it with --memory-limit or UVR_MEMORY_LIMIT)");
}

void InflationBound::claim(uint64_t bytes, const std::string &position, const std::string &what) {
  uint64_t total = 0;
  if (__builtin_add_overflow(claimed_, bytes, &total) || total / maxRatio_ > fileBytes_)
    throw Error(path_, position,
                what + " brings what the file decodes to more than " + std::to_string(maxRatio_) +
                    " times its " + std::to_string(fileBytes_) + " bytes" +
                    (maxRatio_ > 1 ? ", more than any compression allows" : ", more than it holds"));
  if (total > fileBytes_)
    checkMemoryLimit(path_, position, total, what + " with the file's other arrays");
  claimed_ = total;
}

std::string quoteInput(std::string_view text, size_t maxChars) {
  if (text.size() <= maxChars)
    return std::string(text);
  return std::string(text.substr(0, maxChars)) + "... (" + std::to_string(text.size()) + " characters)";
}

} // namespace uvr
