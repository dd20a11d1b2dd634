// Reading files: whole at once (what the text readers parse), at given offsets straight into place (what
// the binary readers do, to copy each byte once), or mapped in place (for a reader that only reads them).
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
  friend class MappedFile;

  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

/// A regular file mapped read-only: its bytes are the page cache's, with no copy and no fresh memory to fault
/// in. No terminating zero. Throws uvr::Error naming it when it cannot be opened or mapped; a file cut short
/// while mapped raises SIGBUS where its lost bytes are read, as any mapping does.
class MappedFile {
public:
  explicit MappedFile(const std::string &path);
  ~MappedFile();
  MappedFile(const MappedFile &) = delete;
  MappedFile &operator=(const MappedFile &) = delete;

  const uint8_t *data() const { return data_; }
  uint64_t size() const { return size_; }

private:
  const uint8_t *data_ = nullptr;
  uint64_t size_ = 0;
};

/// Throws uvr::Error naming `path` unless it is a regular file (stat alone: opening a FIFO would block).
void checkRegularFile(const std::string &path);

/// Reads a regular file; throws uvr::Error naming it when it cannot be opened or read.
FileBuffer readFile(const std::string &path);

} // namespace uvr
