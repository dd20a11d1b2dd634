// The options `uvr render` and `uvr view` share, and how they become the renderer's inputs.
#pragma once

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/mesh.h>
#include <uvr/settings.h>

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace uvr {

struct RenderOptions {
  std::string mesh;
  int timeStep = 0;      ///< the step --time-step names when it names one
  std::string timeSteps; ///< --time-step as given (`uvr render`: also a range, see parseTimeSteps); empty: 0
  std::string field;
  std::string tf;
  std::string tfName;
  std::vector<float> range;
  std::string mode = "full";
  std::string compositing = "auto";
  std::string steps = "auto";
  float s1 = 0.f, s2 = 0.f, p = 0.f, unit = 0.f;
  uint32_t leafSize = kAutoLeafSize;
  std::string size = "1024x1024";
  std::string eye, at, up;
  std::string view; ///< a named view (cameraViewNames); empty: +z, the reset camera
  float fovy = 30.f;
  std::string background = "0,0,0";
  std::string backend = "cpu";
  bool shade = false;
  std::string light;              ///< X,Y,Z in camera space; empty: the headlight
  std::optional<std::string> iso; ///< V[,V...]; unset: no isosurfaces (given empty is an error)
  std::string isoColor;           ///< R,G,B; empty: the transfer function's colour at each value
  float isoOpacity = 1.f;
  bool isoOnly = false;
};

/// Registers MESH and the options that describe a view (field, transfer function, sampling, camera, size);
/// with `timeRanges`, --time-step takes a range of steps too.
void addRenderOptions(CLI::App *command, RenderOptions &options, bool timeRanges = false);

/// A mesh loaded for rendering: lower-dimensional cells reported, the field chosen.
struct LoadedMesh {
  VolumeMesh mesh;
  int fieldIndex = 0;
  double loadMs = 0.0;
};
LoadedMesh loadForRendering(const RenderOptions &options);
/// The same for step `timeStep` rather than --time-step's.
LoadedMesh loadForRendering(const RenderOptions &options, int timeStep);

/// Warns on stderr when the --s1 given takes far more samples along the mesh's diagonal than the default.
void warnOfSmallStep(const FrameSettings &settings, const VolumeMesh &mesh);

/// Image size, background, backend, mode and sampling (0 for s1, s2, p and unit: the mesh's defaults),
/// checked before the mesh is loaded, with the camera's options and --range (errors name the option).
FrameSettings parseFrameSettings(const RenderOptions &options);

/// The preset --tf and --tf-name choose (errors name the options).
ColorMap chooseTransferFunction(const RenderOptions &options);

/// The --range, or the default range of the mesh's field `fieldIndex` (defaultTransferRange; a constant
/// field is reported on stderr).
ValueRange transferRange(const RenderOptions &options, const VolumeMesh &mesh, int fieldIndex);
/// The same for a field of range `data` named `name`.
ValueRange transferRange(const RenderOptions &options, ValueRange data, const std::string &name);

/// ParaView's reset camera for the mesh from --view, with --eye, --at, --up and --fovy applied.
Camera chooseCamera(const RenderOptions &options, const VolumeMesh &mesh);
/// The same for a mesh of bounds `bounds`.
Camera chooseCamera(const RenderOptions &options, const Box3f &bounds);

} // namespace uvr
