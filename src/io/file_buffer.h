// Reading files: whole at once (what the text readers parse), or at given offsets straight into place (what
// the binary readers do, to copy each byte once).
#pragma once

#include "core/buffer.h"

#include <cstdint>
#include <string>

namespace uvr {

struct FileBuffer {
  Buffer<uint8_t> data; ///< the whole file plus a terminating zero
  uint64_t size = 0;

  char *chars() { return reinterpret_cast<char *>(data.data()); }
  const char *chars() const { return reinterpret_cast<const char *>(data.data()); }
};

/// A regular file open for reading; throws uvr::Error naming it when it cannot be opened or read.
class InputFile {
public:
  explicit InputFile(const std::string &path);
  ~InputFile();
  InputFile(const InputFile &) = delete;
  InputFile &operator=(const InputFile &) = delete;

  uint64_t size() const { return size_; }
  const std::string &path() const { return path_; }
  /// Copies bytes [offset, offset + n) to dst; the caller checks that they lie inside the file.
  void read(uint64_t offset, void *dst, uint64_t n) const;

private:
  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

/// Reads a regular file; throws uvr::Error naming it when it cannot be opened or read.
FileBuffer readFile(const std::string &path);

} // namespace uvr
