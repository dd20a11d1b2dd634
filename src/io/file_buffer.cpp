#include "io/file_buffer.h"

#include "core/error.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace uvr {

InputFile::InputFile(const std::string &path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0)
    throw Error(path, "", std::string("cannot open file: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd_, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd_);
    throw Error(path, "", "cannot open file: not a regular file");
  }
  size_ = uint64_t(info.st_size);
}

InputFile::~InputFile() { ::close(fd_); }

void InputFile::read(uint64_t offset, void *dst, uint64_t n) const {
  auto *out = static_cast<uint8_t *>(dst);
  uint64_t done = 0;
  while (done < n) {
    ssize_t got = ::pread(fd_, out + done, n - done, off_t(offset + done));
    if (got < 0 && errno == EINTR)
      continue;
    if (got <= 0)
      throw Error(path_, "byte " + std::to_string(offset + done),
                  "cannot read file: " +
                      std::string(got < 0 ? std::strerror(errno) : "file shrank while reading"));
    done += uint64_t(got);
  }
}

FileBuffer readFile(const std::string &path) {
  InputFile input(path);
  FileBuffer file;
  file.size = input.size();
  file.data = std::make_unique_for_overwrite<uint8_t[]>(file.size + 1);
  input.read(0, file.data.get(), file.size);
  file.data[file.size] = 0;
  return file;
}

} // namespace uvr
