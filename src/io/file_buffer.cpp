#include "io/file_buffer.h"

#include "core/error.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace uvr {

FileBuffer readFile(const std::string &path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw Error(path, "", std::string("cannot open file: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    throw Error(path, "", "cannot open file: not a regular file");
  }
  FileBuffer file;
  file.size = uint64_t(info.st_size);
  file.data = std::make_unique_for_overwrite<uint8_t[]>(file.size + 1);
  uint64_t done = 0;
  while (done < file.size) {
    ssize_t got = ::read(fd, file.data.get() + done, file.size - done);
    if (got < 0 && errno == EINTR)
      continue;
    if (got <= 0) {
      std::string why = got < 0 ? std::strerror(errno) : "file shrank while reading";
      ::close(fd);
      throw Error(path, "", "cannot read file: " + why);
    }
    done += uint64_t(got);
  }
  ::close(fd);
  file.data[file.size] = 0;
  return file;
}

} // namespace uvr
