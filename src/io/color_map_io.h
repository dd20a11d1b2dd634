// Colour-map preset files: ParaView's colour-map JSON, read and written.
#pragma once

#include "render/color_map.h"

#include <string>
#include <vector>

namespace uvr {

/// Reads ParaView's colour-map preset JSON (an array of presets, or one preset object). Takes the preset
/// named `name`, or the first with RGBPoints when `name` is empty. Throws uvr::Error naming the file.
ColorMap readColorMapFile(const std::string &path, const std::string &name = {});

/// Every preset of a ParaView preset file that has RGBPoints, in file order (the viewer's preset list).
std::vector<ColorMap> readColorMapPresets(const std::string &path);

/// Writes `map` as a ParaView preset file (an array holding one preset) that ParaView's *Import preset* and
/// readColorMapFile read back. Throws uvr::Error when the file cannot be written.
void writeColorMapFile(const std::string &path, const ColorMap &map);

/// The preset `tf`: a ParaView preset file (taking preset `tfName`, or the first) or a built-in name; the
/// default built-in one when `tf` is empty.
ColorMap chooseColorMap(const std::string &tf, const std::string &tfName = {});

} // namespace uvr
