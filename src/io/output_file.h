// A file being written, for the mesh writers: buffered, with every failure turned into uvr::Error.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace uvr {

class OutputFile {
public:
  /// Creates or truncates `path`.
  explicit OutputFile(const std::string &path);
  /// Closes without reporting errors: call close() to learn whether everything reached the file.
  ~OutputFile();
  OutputFile(const OutputFile &) = delete;
  OutputFile &operator=(const OutputFile &) = delete;

  void write(const void *data, uint64_t n);
  template <typename T> void writeValue(const T &value) { write(&value, sizeof(T)); }
  uint64_t written() const { return written_; }
  void close();

private:
  [[noreturn]] void fail(const std::string &what);

  std::string path_;
  std::FILE *file_ = nullptr;
  uint64_t written_ = 0;
};

} // namespace uvr
