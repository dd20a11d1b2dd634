#include "fuzz_input.h"
#include "io/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  return uvr::fuzz::readInput(data, size, [](const std::string &path) { return uvr::readNifti(path); });
}
