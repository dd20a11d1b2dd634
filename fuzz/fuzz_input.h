// libFuzzer entry points for the mesh readers. The readers take a path, so each input is written to an
// in-memory file (memfd) and read back through /proc/self/fd: no disk traffic, nothing left behind.
#pragma once

#include "mesh/mesh.h"
#include <uvr/error.h>

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <type_traits>

namespace uvr::fuzz {

/// The path of an in-memory file holding exactly `data`.
inline const std::string &inputFile(const uint8_t *data, size_t size) {
  static const int fd = ::memfd_create("uvr_fuzz_input", MFD_CLOEXEC);
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  if (fd < 0 || ::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != ssize_t(size))
    std::abort();
  return path;
}

/// Reads the input with `read` and, where it gives an unstructured grid, builds the mesh: a uvr::Error is the
/// expected answer to a bad file; anything else (another exception, a crash, a sanitizer report) is a
/// finding.
template <typename Read> int readInput(const uint8_t *data, size_t size, Read &&read) {
  const std::string &path = inputFile(data, size);
  try {
    if constexpr (std::is_same_v<decltype(read(path)), UnstructuredGrid>)
      buildMesh(read(path), path);
    else
      read(path);
  } catch (const Error &) {
  }
  return 0;
}

} // namespace uvr::fuzz
