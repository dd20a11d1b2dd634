// Transfer-function presets as ParaView defines them, a few built-in ones, and their evaluation. Preset files
// (ParaView's colour-map JSON) are read and written by io/color_map_io.h.
#pragma once

#include "core/vec.h"

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

/// Throws uvr::Error naming `file` and `position` unless `map` can be sampled: RGBPoints given, both point
/// lists of whole points (4 values each) in non-decreasing x, midpoints and sharpness in [0, 1], and a known
/// colour space.
void checkColorMap(const ColorMap &map, const std::string &file, const std::string &position);

/// Names of the built-in presets, the default first.
std::vector<std::string> builtinColorMapNames();

/// A built-in preset by name (case-insensitive); throws uvr::Error listing the names when unknown.
ColorMap builtinColorMap(const std::string &name);

/// Samples colour and opacity at `count` evenly spaced points spanning the preset's own x range, first to
/// last control point. Colour is interpolated in the preset's colour space, opacity as VTK's
/// vtkPiecewiseFunction does it (midpoint and sharpness). Opacity is per opacity unit distance.
std::vector<Vec4f> sampleColorMap(const ColorMap &map, int count);

} // namespace uvr
