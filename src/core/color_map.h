// Transfer-function presets: the public ColorMap and its functions, and the check the preset reader adds.
#pragma once

#include <uvr/color_map.h>

#include <string>

namespace uvr {

/// Throws uvr::Error naming `file` and `position` unless `map` can be sampled: RGBPoints given, both point
/// lists of whole points (4 values each) in non-decreasing x, midpoints and sharpness in [0, 1], and a known
/// colour space.
void checkColorMap(const ColorMap &map, const std::string &file, const std::string &position);

} // namespace uvr
