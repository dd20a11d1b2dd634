#include "io/output_file.h"

#include <uvr/error.h>

#include <cerrno>
#include <cstring>

namespace uvr {

OutputFile::OutputFile(const std::string &path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_)
    throw Error(path, "", std::string("cannot create file: ") + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

OutputFile::~OutputFile() {
  if (file_)
    std::fclose(file_);
}

void OutputFile::fail(const std::string &what) {
  const std::string reason = std::strerror(errno);
  std::fclose(file_);
  file_ = nullptr;
  throw Error(path_, "byte " + std::to_string(written_), what + ": " + reason);
}

void OutputFile::write(const void *data, uint64_t n) {
  if (n > 0 && std::fwrite(data, 1, n, file_) != n)
    fail("cannot write file");
  written_ += n;
}

void OutputFile::close() {
  if (std::fflush(file_) != 0)
    fail("cannot write file");
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0)
    throw Error(path_, "", std::string("cannot write file: ") + std::strerror(errno));
}

} // namespace uvr
