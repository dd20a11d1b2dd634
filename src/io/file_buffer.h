// A whole file in memory, read at once: what the readers parse.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace uvr {

struct FileBuffer {
  std::unique_ptr<uint8_t[]> data; ///< the whole file plus a terminating zero
  uint64_t size = 0;

  char *chars() const { return reinterpret_cast<char *>(data.get()); }
};

/// Reads a regular file; throws uvr::Error naming it when it cannot be opened or read.
FileBuffer readFile(const std::string &path);

} // namespace uvr
