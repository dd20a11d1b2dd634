#include <uvr/error.h>

#include <uvr/color_map.h>

#include <filesystem>

namespace uvr {

ColorMap chooseColorMap(const std::string &tf, const std::string &tfName) {
  if (tf.empty())
    return builtinColorMap(builtinColorMapNames().front());
  // Without an error code, exists() throws std::filesystem_error for e.g. a name too long.
  std::error_code error;
  const bool exists = std::filesystem::exists(tf, error);
  if (exists)
    return readColorMapFile(tf, tfName);
  if (error && error != std::errc::no_such_file_or_directory)
    throw Error(tf, "", "cannot open transfer-function file: " + error.message());
  if (tf.size() > 5 && tf.substr(tf.size() - 5) == ".json")
    throw Error(tf, "", "cannot open transfer-function file");
  return builtinColorMap(tf);
}

ColorMap colorMapFromTable(std::span<const Vec4f> rgba) {
  if (rgba.size() < 2)
    throw Error("a transfer-function table needs at least 2 entries");
  ColorMap map;
  map.name = "table";
  const size_t last = rgba.size() - 1;
  for (size_t i = 0; i < rgba.size(); ++i) {
    const float x = float(i) / float(last);
    map.rgbPoints.insert(map.rgbPoints.end(), {x, rgba[i].x, rgba[i].y, rgba[i].z});
    map.opacityPoints.insert(map.opacityPoints.end(), {x, rgba[i].w, 0.5f, 0.f}); // linear in between
  }
  return map;
}

} // namespace uvr
