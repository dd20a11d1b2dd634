// `uvr render` over time steps and camera paths: one PNG per frame, numbered, and a video when ffmpeg is
// found.
#pragma once

#include "render_options.h"

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/settings.h>

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace uvr {

/// --time-step as `uvr render` takes it: one step N, the steps A to B (both included) every STEP
/// (A:B[:STEP]), or all of them.
struct TimeSteps {
  int first = 0, last = 0, stride = 1;
  bool all = false;
  bool range = false; ///< A:B[:STEP] or all: a movie, even of one step
};
/// Throws uvr::Error naming --time-step for malformed text.
TimeSteps parseTimeSteps(const std::string &text);
/// The steps in order; `count` is the number the mesh holds. Throws uvr::Error naming --time-step when a step
/// is past the last.
std::vector<int> expandTimeSteps(const TimeSteps &steps, int count, const std::string &mesh);

/// A camera keyframe of --camera-path: each field missing from the file takes the command line's camera.
struct Keyframe {
  std::optional<Vec3f> eye, at, up;
  std::optional<float> fovy;
  std::optional<int> frame;
};
/// Reads a JSON list of keyframes (docs/cli.md); throws uvr::Error naming the file and --camera-path.
std::vector<Keyframe> readCameraPath(const std::string &path);

/// The frames a path of keyframes spans: the last keyframe's frame + 1 when they are numbered, or
/// kFramesPerKeyframe between consecutive keyframes.
constexpr int kFramesPerKeyframe = 30;
int cameraPathFrames(const std::vector<Keyframe> &keys);
/// The camera at `frame` of `frames` along the keyframes, Catmull-Rom between them (the field of view
/// linear): each keyframe's camera exactly at its frame. Unnumbered keyframes are spread evenly over the
/// frames.
Camera cameraPathAt(const std::vector<Keyframe> &keys, const Camera &base, int frame, int frames);

/// `camera` turned by `degrees` about the axis along its view-up through its focal point (counter-clockwise
/// seen from above); 0 degrees leaves it as it is.
Camera orbitCamera(const Camera &camera, double degrees);

/// `-o OUT.png` as the name of frame `frame`: OUT_0000.png.
std::string frameFileName(const std::string &output, int frame);

struct MovieOptions {
  float orbit = 0.f; ///< degrees per frame; 0: none
  std::string cameraPath;
  int fps = 24;
};

/// Registers --orbit, --camera-path and --fps on `uvr render`.
void addMovieOptions(CLI::App *command, MovieOptions &options);

/// Whether the command makes a movie: a range of time steps, an orbit or a camera path.
bool isMovie(const RenderOptions &view, const MovieOptions &movie);

/// What `uvr render` writes and how many frames it was asked for.
struct MovieOutputs {
  std::string output, heatmap, stats;
  std::optional<int> frames; ///< --frames, when given
};

/// Renders the frames, writes them and the video, and the statistics (docs/cli.md, "Movies").
void renderMovie(const RenderOptions &view, const MovieOptions &movie, FrameSettings settings,
                 const ColorMap &colorMap, const MovieOutputs &outputs);

} // namespace uvr
