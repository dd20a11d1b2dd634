#include "io/file_buffer.h"

#include <uvr/error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace uvr {

void checkRegularFile(const std::string &path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0)
    throw Error(path, "", std::string("cannot open file: ") + std::strerror(errno));
  if (!S_ISREG(info.st_mode))
    throw Error(path, "", "cannot open file: not a regular file");
}

InputFile::InputFile(const std::string &path) : path_(path) {
  // A FIFO or device would block open() itself: refused by stat first, and opened without blocking should
  // one replace the file in between (fstat then refuses it).
  checkRegularFile(path);
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
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

MappedFile::MappedFile(const std::string &path) {
  const InputFile input(path);
  if (input.size() == 0)
    return; // mmap refuses an empty range
  // Populated up front: one call maps every page instead of a fault for each run of them.
  void *p = ::mmap(nullptr, input.size(), PROT_READ, MAP_PRIVATE | MAP_POPULATE, input.fd_, 0);
  if (p == MAP_FAILED)
    throw Error(path, "", std::string("cannot read file: ") + std::strerror(errno));
  data_ = static_cast<const uint8_t *>(p);
  size_ = input.size();
}

MappedFile::~MappedFile() {
  if (data_)
    ::munmap(const_cast<uint8_t *>(data_), size_);
}

FileBuffer readFile(const std::string &path) {
  InputFile input(path);
  FileBuffer file;
  file.size = input.size();
  file.data = Buffer<uint8_t>(file.size + 1);
  // In parallel chunks: the copy from the page cache and the buffer's page faults are a good part of a
  // binary file's load.
  constexpr uint64_t kChunkBytes = uint64_t(4) << 20;
  tbb::parallel_for(uint64_t(0), (file.size + kChunkBytes - 1) / kChunkBytes, [&](uint64_t chunk) {
    const uint64_t begin = chunk * kChunkBytes;
    input.read(begin, file.data.data() + begin, std::min(kChunkBytes, file.size - begin));
  });
  file.data[file.size] = 0;
  return file;
}

} // namespace uvr
