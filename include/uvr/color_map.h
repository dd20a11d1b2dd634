// Transfer-function presets: ParaView's colour-map JSON, a few built-in ones, and tables.
#pragma once

#include <uvr/vec.h>

#include <span>

#include <string>
#include <vector>

namespace uvr {

/// A preset as ParaView stores it: colour and opacity control points in any scalar units; they are stretched
/// over the data range when applied.
struct ColorMap {
  std::string name;
  std::vector<float> rgbPoints;     ///< x, r, g, b per point
  std::vector<float> opacityPoints; ///< x, opacity, midpoint, sharpness per point; empty = opaque ramp 0..1
  std::string colorSpace = "RGB";   ///< RGB, HSV, Lab, CIELAB, Diverging, Lab/CIEDE2000, Step
  Vec3f nanColor{1.f, 1.f, 0.f};
};

/// Reads ParaView's colour-map preset JSON (an array of presets, or one preset object). Takes the preset
/// named `name`, or the first with RGBPoints when `name` is empty. Throws uvr::Error naming the file.
ColorMap readColorMapFile(const std::string &path, const std::string &name = {});

/// Every preset of a ParaView preset file that has RGBPoints, in file order (the viewer's preset list).
std::vector<ColorMap> readColorMapPresets(const std::string &path);

/// Writes `map` as a ParaView preset file (an array holding one preset) that ParaView's *Import preset* and
/// readColorMapFile read back. Throws uvr::Error when the file cannot be written.
void writeColorMapFile(const std::string &path, const ColorMap &map);

/// Names of the built-in presets, the default first.
std::vector<std::string> builtinColorMapNames();

/// A built-in preset by name (case-insensitive); throws uvr::Error listing the names when unknown.
ColorMap builtinColorMap(const std::string &name);

/// Samples colour and opacity at `count` evenly spaced points spanning the preset's own x range, first to
/// last control point. Colour is interpolated in the preset's colour space, opacity as VTK's
/// vtkPiecewiseFunction does it (midpoint and sharpness). Opacity is per opacity unit distance.
std::vector<Vec4f> sampleColorMap(const ColorMap &map, int count);

/// The preset `tf`: a ParaView preset file (taking preset `tfName`, or the first with RGBPoints) or a
/// built-in name; the default built-in one when `tf` is empty. Throws uvr::Error naming the file or listing
/// the names.
ColorMap chooseColorMap(const std::string &tf, const std::string &tfName = {});

/// A preset from a table of colours and opacities (per opacity unit distance) at evenly spaced values, as
/// VTK's colour and opacity functions are sampled: entry i at x = i / (n - 1), interpolated linearly in RGB.
/// Needs at least 2 entries.
ColorMap colorMapFromTable(std::span<const Vec4f> rgba);

} // namespace uvr
