// The interactive viewer behind `uvr view`: a GLFW window with the rendered frame, Dear ImGui controls and a
// colour legend. Nothing here exposes GLFW or OpenGL, so the command compiles without them.
#pragma once

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/mesh.h>
#include <uvr/settings.h>

#include <string>
#include <vector>

namespace uvr {

struct ViewerSetup {
  VolumeMesh mesh;
  std::string meshPath;
  int fieldIndex = 0;
  uint32_t leafSize = kAutoLeafSize;
  float defaultStep = 1.f;       ///< VolumeMesh::defaultStep: what s1 = 0 etc. mean
  float defaultUnit = 1.f;       ///< defaultUnitDistance: what unit = 0 means
  Camera camera;                 ///< the starting camera
  FrameSettings settings;        ///< size of the image region, background, sampling (defaults filled in)
  ColorMap colorMap;             ///< the starting preset
  std::vector<ColorMap> presets; ///< the --tf file's presets, listed after the built-in ones
  ValueRange range;              ///< the starting range
  std::string script;            ///< see view_script.h
  std::string screenshotPrefix;
};

/// Opens the window and runs until it is closed or the script ends. Throws uvr::Error when no window can be
/// opened or the script fails.
void runViewer(const ViewerSetup &setup);

} // namespace uvr
