// Transfer-function preset files (ParaView's colour-map JSON), as `--tf FILE` reads them.
#include "fuzz_input.h"

#include <uvr/color_map.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string &path = uvr::fuzz::inputFile(data, size);
  try {
    for (const uvr::ColorMap &map : uvr::readColorMapPresets(path))
      uvr::sampleColorMap(map, 64);
  } catch (const uvr::Error &) {
  }
  return 0;
}
