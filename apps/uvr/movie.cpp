#include "movie.h"

#include "front_end.h"
#include "option_checks.h"

#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/io.h>
#include <uvr/renderer.h>
#include <uvr/system.h>

#include <nlohmann/json.hpp>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

extern char **environ;

namespace uvr {

namespace {

/// A non-negative integer of at most 9 digits (no sign, no spaces), or nothing.
std::optional<int> parseStepNumber(const std::string &text) {
  if (text.empty() || text.size() > 9 ||
      !std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    return std::nullopt;
  return std::stoi(text);
}

} // namespace

TimeSteps parseTimeSteps(const std::string &text) {
  const auto fail = [&text]() -> TimeSteps {
    throw Error("expected a step N >= 0, a range A:B or A:B:STEP (A <= B, STEP >= 1) or all, got '" + text +
                "'");
  };
  TimeSteps steps;
  if (text == "all") {
    steps.all = steps.range = true;
    return steps;
  }
  std::vector<std::optional<int>> parts;
  size_t start = 0;
  for (size_t colon; (colon = text.find(':', start)) != std::string::npos; start = colon + 1)
    parts.push_back(parseStepNumber(text.substr(start, colon - start)));
  parts.push_back(parseStepNumber(text.substr(start)));
  if (parts.size() > 3 || std::any_of(parts.begin(), parts.end(), [](const auto &p) { return !p; }))
    return fail();
  steps.first = *parts[0];
  steps.last = parts.size() > 1 ? *parts[1] : steps.first;
  steps.stride = parts.size() > 2 ? *parts[2] : 1;
  steps.range = parts.size() > 1;
  if (steps.last < steps.first || steps.stride < 1)
    return fail();
  return steps;
}

std::vector<int> expandTimeSteps(const TimeSteps &steps, int count, const std::string &mesh) {
  const int last = steps.all ? count - 1 : steps.last;
  if (last >= count)
    throw Error(mesh, "",
                "--time-step: step " + std::to_string(last) + " is past the last step, " +
                    std::to_string(count - 1));
  std::vector<int> list;
  for (int step = steps.all ? 0 : steps.first; step <= last; step += steps.stride)
    list.push_back(step);
  return list;
}

namespace {

Vec3f vectorOf(const nlohmann::json &value, const std::string &what) {
  if (!value.is_array() || value.size() != 3 ||
      !std::all_of(value.begin(), value.end(), [](const nlohmann::json &v) { return v.is_number(); }))
    throw Error(what + ": expected [X, Y, Z]");
  const Vec3f v{value[0].get<float>(), value[1].get<float>(), value[2].get<float>()};
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw Error(what + ": expected three finite numbers");
  return v;
}

} // namespace

std::vector<Keyframe> readCameraPath(const std::string &path) {
  std::ifstream in(path);
  if (!in)
    throw Error(path, "", std::string("--camera-path: cannot read: ") + std::strerror(errno));
  std::vector<Keyframe> keys;
  try {
    const nlohmann::json list = nlohmann::json::parse(in);
    if (!list.is_array() || list.empty())
      throw Error("expected a JSON list of keyframes such as {\"eye\": [X, Y, Z]}");
    for (size_t i = 0; i < list.size(); ++i) {
      const nlohmann::json &item = list[i];
      const std::string where = "keyframe " + std::to_string(i);
      if (!item.is_object())
        throw Error(where + ": expected an object");
      for (const auto &[name, value] : item.items())
        if (name != "eye" && name != "at" && name != "up" && name != "fovy" && name != "frame")
          throw Error(where + ": unknown key '" + name + "' (eye, at, up, fovy, frame)");
      Keyframe key;
      for (const auto &[name, field] : {std::pair{"eye", &key.eye}, {"at", &key.at}, {"up", &key.up}})
        if (item.contains(name))
          *field = vectorOf(item[name], where + ", " + name);
      if (item.contains("fovy")) {
        const nlohmann::json &fovy = item["fovy"];
        if (!fovy.is_number() || !(fovy.get<double>() > 0.0 && fovy.get<double>() < 180.0))
          throw Error(where + ", fovy: expected a number of degrees between 0 and 180");
        key.fovy = fovy.get<float>();
      }
      if (item.contains("frame")) {
        const nlohmann::json &frame = item["frame"];
        if (!frame.is_number_integer() || frame.get<int64_t>() < 0 || frame.get<int64_t>() > 1000000)
          throw Error(where + ", frame: expected an integer from 0 to 10^6");
        key.frame = frame.get<int>();
      }
      if (i > 0 && key.frame.has_value() != keys[0].frame.has_value())
        throw Error(where + ": give every keyframe a frame, or none");
      if (key.frame && (i == 0 ? *key.frame != 0 : *key.frame <= *keys.back().frame))
        throw Error(where +
                    ", frame: the first keyframe's frame is 0, and each later one's above the one before");
      keys.push_back(key);
    }
  } catch (const nlohmann::json::exception &e) {
    throw Error(path, "", std::string("--camera-path: ") + e.what());
  } catch (const Error &e) {
    throw Error(path, "", std::string("--camera-path: ") + e.what());
  }
  return keys;
}

int cameraPathFrames(const std::vector<Keyframe> &keys) {
  if (keys.front().frame)
    return *keys.back().frame + 1;
  return kFramesPerKeyframe * int(keys.size() - 1) + 1;
}

namespace {

/// The keyframe's camera, what it leaves out taken from `base`.
Camera keyCamera(const Keyframe &key, const Camera &base) {
  Camera camera = base;
  camera.eye = key.eye.value_or(base.eye);
  camera.at = key.at.value_or(base.at);
  camera.up = key.up.value_or(base.up);
  camera.fovy = key.fovy.value_or(base.fovy);
  return camera;
}

/// Uniform Catmull-Rom between b (t = 0) and c (t = 1), a and d the points before and after.
Vec3f catmullRom(const Vec3f &a, const Vec3f &b, const Vec3f &c, const Vec3f &d, double t) {
  const auto axis = [t](double p0, double p1, double p2, double p3) {
    return float(0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t +
                        (3.0 * p1 - p0 - 3.0 * p2 + p3) * t * t * t));
  };
  return {axis(a.x, b.x, c.x, d.x), axis(a.y, b.y, c.y, d.y), axis(a.z, b.z, c.z, d.z)};
}

} // namespace

Camera cameraPathAt(const std::vector<Keyframe> &keys, const Camera &base, int frame, int frames) {
  const int n = int(keys.size());
  std::vector<int> at(size_t(n), 0); // each keyframe's frame
  for (int i = 0; i < n; ++i)
    at[size_t(i)] = keys[size_t(i)].frame ? *keys[size_t(i)].frame
                    : n == 1              ? 0
                                          : int(std::lround(double(i) * (frames - 1) / (n - 1)));
  int segment = 0; // keyframes segment and segment + 1 span the frame
  while (segment + 1 < n && at[size_t(segment) + 1] <= frame)
    ++segment;
  if (segment + 1 == n || at[size_t(segment)] == frame)
    return keyCamera(keys[size_t(segment)], base);
  const auto camera = [&](int i) { return keyCamera(keys[size_t(std::clamp(i, 0, n - 1))], base); };
  const Camera a = camera(segment - 1), b = camera(segment), c = camera(segment + 1), d = camera(segment + 2);
  const double t =
      double(frame - at[size_t(segment)]) / double(at[size_t(segment) + 1] - at[size_t(segment)]);
  Camera result;
  result.eye = catmullRom(a.eye, b.eye, c.eye, d.eye, t);
  result.at = catmullRom(a.at, b.at, c.at, d.at, t);
  result.up = catmullRom(a.up, b.up, c.up, d.up, t);
  result.fovy = float(double(b.fovy) + (double(c.fovy) - double(b.fovy)) * t);
  return result;
}

Camera orbitCamera(const Camera &camera, double degrees) {
  if (degrees == 0.0)
    return camera;
  const double angle = degrees * 3.14159265358979323846 / 180.0;
  const double c = std::cos(angle), s = std::sin(angle);
  const double ux = camera.up.x, uy = camera.up.y, uz = camera.up.z;
  const double norm = std::sqrt(ux * ux + uy * uy + uz * uz);
  const double kx = ux / norm, ky = uy / norm, kz = uz / norm;
  const double vx = double(camera.eye.x) - camera.at.x, vy = double(camera.eye.y) - camera.at.y,
               vz = double(camera.eye.z) - camera.at.z;
  // Rodrigues' rotation of the eye's offset from the focal point about the unit axis k.
  const double dot = kx * vx + ky * vy + kz * vz;
  const double rx = vx * c + (ky * vz - kz * vy) * s + kx * dot * (1.0 - c);
  const double ry = vy * c + (kz * vx - kx * vz) * s + ky * dot * (1.0 - c);
  const double rz = vz * c + (kx * vy - ky * vx) * s + kz * dot * (1.0 - c);
  Camera turned = camera;
  turned.eye = {float(camera.at.x + rx), float(camera.at.y + ry), float(camera.at.z + rz)};
  return turned;
}

namespace {

/// `output` without its extension (".png", in any case: checked before).
std::string withoutExtension(const std::string &output) { return output.substr(0, output.size() - 4); }

} // namespace

std::string frameFileName(const std::string &output, int frame) {
  char number[16];
  std::snprintf(number, sizeof number, "_%04d", frame);
  return withoutExtension(output) + number + output.substr(output.size() - 4);
}

void addMovieOptions(CLI::App *cmd, MovieOptions &o) {
  CLI::Option *orbit =
      cmd->add_option("--orbit", o.orbit,
                      "Movie: turn the camera this many degrees per frame about the view-up axis through the "
                      "focal point (default frames: a full turn)")
          ->check(numberCheck("a number of degrees, not 0, from -360 to 360",
                              [](double v) { return v != 0.0 && std::abs(v) <= 360.0; }));
  cmd->add_option("--camera-path", o.cameraPath,
                  "Movie: the camera through keyframes, a JSON list of {eye, at, up, fovy, frame} "
                  "(docs/cli.md)")
      ->excludes(orbit);
  cmd->add_option("--fps", o.fps, "Frames per second of the video ffmpeg makes of a movie")
      ->check(numberCheck("an integer from 1 to 240",
                          [](double v) { return v >= 1.0 && v <= 240.0 && v == std::floor(v); }))
      ->capture_default_str();
}

bool isMovie(const RenderOptions &view, const MovieOptions &movie) {
  return movie.orbit != 0.f || !movie.cameraPath.empty() ||
         (!view.timeSteps.empty() && parseTimeSteps(view.timeSteps).range);
}

namespace {

/// The frames and how they move, settled before any mesh is loaded.
struct MoviePlan {
  std::vector<int> steps; ///< the time step of each frame
  bool series = false;    ///< whether the frames go through time steps
  std::vector<Keyframe> keys;
  int frames = 1;
};

MoviePlan planMovie(const RenderOptions &view, const MovieOptions &movie, const MovieOutputs &outputs) {
  MoviePlan plan;
  const TimeSteps steps = parseTimeSteps(view.timeSteps.empty() ? "0" : view.timeSteps);
  if (!movie.cameraPath.empty())
    plan.keys = readCameraPath(movie.cameraPath);
  if (steps.range) {
    plan.series = true;
    plan.steps = expandTimeSteps(steps, timeStepCount(view.mesh), view.mesh);
    plan.frames = int(plan.steps.size());
    if (outputs.frames && *outputs.frames != plan.frames)
      throw Error("--frames: a time series has one frame per step, and --time-step " + view.timeSteps +
                  " gives " + std::to_string(plan.frames));
  } else if (outputs.frames) {
    plan.frames = *outputs.frames;
  } else if (movie.orbit != 0.f) {
    plan.frames = std::max(1, int(std::lround(360.0 / std::abs(double(movie.orbit)))));
  } else if (!plan.keys.empty()) {
    plan.frames = cameraPathFrames(plan.keys);
  }
  if (!plan.keys.empty() && plan.keys.front().frame && cameraPathFrames(plan.keys) != plan.frames)
    throw Error(movie.cameraPath, "",
                "--camera-path: the keyframes end at frame " + std::to_string(*plan.keys.back().frame) +
                    " but the movie has " + std::to_string(plan.frames) + " frames (--frames, --time-step)");
  if (!plan.keys.empty() && plan.frames < int(plan.keys.size()))
    throw Error(movie.cameraPath, "",
                "--camera-path: " + std::to_string(plan.keys.size()) + " keyframes need as many frames, " +
                    "the movie has " + std::to_string(plan.frames) + " (--frames, --time-step)");
  if (!plan.series)
    plan.steps.assign(size_t(plan.frames), steps.first);
  return plan;
}

/// One line on a terminal, redrawn after each frame: how far, and the time left at the pace so far.
class FrameProgress {
public:
  explicit FrameProgress(int frames) : frames_(frames), enabled_(isatty(fileno(stderr)) != 0) {}

  void frameDone(int done) {
    if (!enabled_)
      return;
    const double seconds = timer_.milliseconds() / 1000.0;
    const double left = seconds / done * (frames_ - done);
    std::fprintf(stderr, "\ruvr: frame %d of %d, %.1f s, about %.0f s left   ", done, frames_, seconds, left);
    drawn_ = done < frames_;
    if (!drawn_)
      std::fputc('\n', stderr);
    std::fflush(stderr);
  }

  /// Before another message: the line drawn ends.
  void endLine() {
    if (drawn_)
      std::fputc('\n', stderr);
    drawn_ = false;
  }

private:
  Timer timer_;
  int frames_;
  bool enabled_;
  bool drawn_ = false; ///< a line is drawn and not ended
};

/// The PNGs `output` names, OUT_%04d.png, as ffmpeg reads a sequence ('%' doubled).
std::string ffmpegPattern(const std::string &output) {
  std::string pattern;
  for (const char c : withoutExtension(output))
    pattern += c == '%' ? std::string("%%") : std::string(1, c);
  return pattern + "_%04d" + output.substr(output.size() - 4);
}

/// The path of `program` in a folder of $PATH, or nothing.
std::optional<std::string> findOnPath(const std::string &program) {
  const char *path = std::getenv("PATH");
  std::string folders = path ? path : "";
  for (size_t start = 0, end; start <= folders.size(); start = end + 1) {
    end = std::min(folders.find(':', start), folders.size());
    const std::string folder = end > start ? folders.substr(start, end - start) : ".";
    const std::string candidate = folder + "/" + program;
    if (::access(candidate.c_str(), X_OK) == 0)
      return candidate;
  }
  return std::nullopt;
}

/// Encodes the first `frames` frames into `video` with `ffmpeg` (frames beyond, left by an earlier longer
/// movie of the same name, stay out). Throws std::runtime_error when it fails.
void writeVideo(const std::string &ffmpeg, const std::string &output, const std::string &video, int frames,
                int fps) {
  writeWhole(video, [&](const std::string &temporary) {
    const std::string pattern = ffmpegPattern(output);
    // yuv420p, which players expect, needs even sides.
    std::vector<std::string> args = {ffmpeg, "-nostdin", "-y", "-loglevel", "error"};
    args.insert(args.end(), {"-framerate", std::to_string(fps), "-i", pattern});
    args.insert(args.end(), {"-frames:v", std::to_string(frames), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"});
    args.insert(args.end(), {"-pix_fmt", "yuv420p", temporary});
    std::vector<char *> argv;
    for (std::string &arg : args)
      argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int error = posix_spawn(&pid, ffmpeg.c_str(), nullptr, nullptr, argv.data(), environ);
    if (error != 0)
      throw std::runtime_error("cannot run " + ffmpeg + ": " + std::strerror(error));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
      throw std::runtime_error(ffmpeg + " failed to make " + video + " (exit status " +
                               std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                               "); the frames are " + pattern);
  });
}

/// Where a frame's acceleration data came from.
enum class StepUpdate { Kept, Reused, Built };

const char *stepUpdateName(StepUpdate update) {
  return update == StepUpdate::Kept ? "kept" : update == StepUpdate::Reused ? "reused" : "built";
}

nlohmann::json cameraJson(const Camera &c) {
  return {{"eye", {c.eye.x, c.eye.y, c.eye.z}},
          {"at", {c.at.x, c.at.y, c.at.z}},
          {"up", {c.up.x, c.up.y, c.up.z}},
          {"fovy", c.fovy}};
}

} // namespace

void renderMovie(const RenderOptions &view, const MovieOptions &movie, FrameSettings settings,
                 const ColorMap &colorMap, const MovieOutputs &outputs) {
  const MoviePlan plan = planMovie(view, movie, outputs);
  checkOutputPath(frameFileName(outputs.output, 0), "-o");
  if (!outputs.heatmap.empty())
    checkOutputPath(frameFileName(outputs.heatmap, 0), "--heatmap");
  // The stats take the frame's sample totals; per-pixel counts only the heat map (a copy from a GPU each).
  settings.keepOpacity = false;
  settings.keepSamplesPerPixel = !outputs.heatmap.empty();

  // The first step sets what every frame shares: the transfer function's range and the camera. Every
  // frame's camera is checked before any is written.
  std::optional<LoadedMesh> loaded = loadForRendering(view, plan.steps[0]);
  warnOfSmallStep(settings, loaded->mesh);
  const ValueRange range = transferRange(view, loaded->mesh, loaded->fieldIndex);
  const Camera base = chooseCamera(view, loaded->mesh);
  std::vector<Camera> cameras;
  for (int i = 0; i < plan.frames; ++i) {
    const Camera camera = orbitCamera(
        plan.keys.empty() ? base : cameraPathAt(plan.keys, base, i, plan.frames), double(movie.orbit) * i);
    try {
      validateCamera(camera);
    } catch (const Error &e) {
      throw Error(std::string(e.what()) + " at frame " + std::to_string(i) +
                  (plan.keys.empty() ? " (--orbit)" : " (--camera-path)"));
    }
    cameras.push_back(camera);
  }

  std::unique_ptr<VolumeRenderer> renderer;
  bool reportedNewGrid = false;
  FrameProgress progress(plan.frames);
  nlohmann::json frameStats = nlohmann::json::array();
  std::vector<double> renderTimes, kernelTimes;
  FrameResult frame;
  nlohmann::json stats;
  int reused = 0;
  for (int i = 0; i < plan.frames; ++i) {
    const int step = plan.steps[size_t(i)];
    StepUpdate update = StepUpdate::Kept;
    double loadMs = 0.0, updateMs = 0.0;
    if (i == 0 || step != plan.steps[size_t(i) - 1]) {
      if (!loaded)
        loaded = loadForRendering(view, step);
      loadMs = loaded->loadMs;
      const Timer updateTimer;
      if (renderer) {
        try {
          renderer->setField(loaded->mesh, loaded->fieldIndex);
          update = StepUpdate::Reused;
          ++reused;
        } catch (const Error &) { // the grid differs: loadForRendering chose a field that exists
          if (!reportedNewGrid) {
            progress.endLine();
            std::fprintf(stderr,
                         "uvr: time step %d: its points or cells differ from the step before: a new renderer "
                         "is built for it (and for any later such step)\n",
                         step);
          }
          reportedNewGrid = true;
        }
      }
      if (update != StepUpdate::Reused) {
        renderer.reset(); // first: the old and the new acceleration data need not fit together
        renderer = std::make_unique<VolumeRenderer>(loaded->mesh, loaded->fieldIndex, view.leafSize);
        renderer->prepare(settings.backend);
        renderer->setTransferFunction(colorMap, range);
        update = StepUpdate::Built;
      }
      updateMs = updateTimer.milliseconds();
      loaded.reset();
    }
    const Camera &camera = cameras[size_t(i)];
    renderer->render(camera, settings, frame);

    const std::string output = frameFileName(outputs.output, i);
    nlohmann::json entry = frameStatsJson(frame.stats);
    entry["frame"] = i;
    entry["output"] = output;
    entry["time_step"] = step;
    entry["load_ms"] = loadMs;
    entry["step_update_ms"] = updateMs;
    entry["acceleration"] = stepUpdateName(update);
    entry["camera"] = cameraJson(camera);
    if (settings.backend == Backend::Cuda)
      entry["gpu_kernel_ms"] = frame.stats.gpuKernelMs;
    if (i == 0) {
      stats = frameStatsJson(frame.stats);
      stats["load_ms"] = loadMs;
      stats["time_step"] = step;
    }
    frameStats.push_back(std::move(entry));
    renderTimes.push_back(frame.stats.renderMs);
    kernelTimes.push_back(frame.stats.gpuKernelMs);

    if (!outputs.heatmap.empty()) {
      const Image heatmap = heatmapImage(frame.samplesPerPixel, settings.width, settings.height);
      writeWhole(frameFileName(outputs.heatmap, i),
                 [&](const std::string &temporary) { writePng(temporary, heatmap); });
    }
    writeWhole(output, [&](const std::string &temporary) { writePng(temporary, frame.image); });
    progress.frameDone(i + 1);
  }

  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const std::optional<std::string> ffmpeg = findOnPath("ffmpeg");
  const std::string video = withoutExtension(outputs.output) + ".mp4";
  if (ffmpeg)
    writeVideo(*ffmpeg, outputs.output, video, plan.frames, movie.fps);
  const std::string written =
      ffmpegPattern(outputs.output) + (ffmpeg ? " and " + video : " (no ffmpeg: no video)");
  const std::string kept =
      plan.series ? ", " + std::to_string(reused) + " steps kept the acceleration data" : std::string();
  std::fprintf(stderr, "uvr: %s %dx%d, %d frames %s, %.1f ms/frame (median)%s\n", modeName(settings.mode),
               settings.width, settings.height, plan.frames, written.c_str(), median(renderTimes),
               kept.c_str());
  if (!outputs.stats.empty()) {
    stats["render_ms"] = median(renderTimes);
    stats["frames"] = plan.frames;
    if (settings.backend == Backend::Cuda)
      stats["gpu_kernel_ms"] = median(kernelTimes);
    stats["video"] = ffmpeg ? nlohmann::json(video) : nlohmann::json(nullptr);
    stats["frame_stats"] = std::move(frameStats);
    writeWhole(outputs.stats, [&](const std::string &temporary) {
      std::ofstream out(temporary);
      out << stats.dump(2) << '\n';
      out.close();
      if (!out)
        throw Error(outputs.stats, "", std::string("cannot write statistics: ") + std::strerror(errno));
    });
  }
}

} // namespace uvr
