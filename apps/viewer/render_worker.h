// Renders the viewer's frames on a background thread with progressive refinement: each new view is drawn
// first at a quarter of the resolution, and at full resolution once it has stayed unchanged for a moment.
#pragma once

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/renderer.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

namespace uvr {

/// Everything that determines a frame.
struct ViewState {
  Camera camera;
  ColorMap colorMap;
  ValueRange range;
  FrameSettings settings; ///< at full resolution
};

struct ViewerFrame {
  FrameResult frame;
  int scale = 1;        ///< 1: full resolution; kPreviewScale: the preview
  uint64_t version = 0; ///< of the ViewState drawn
  nlohmann::json stats; ///< frameStatsJson of this frame
  std::string error;    ///< why the frame could not be drawn (e.g. s2 < s1), else empty
};

class RenderWorker {
public:
  static constexpr int kPreviewScale = 4;
  /// How long a view must stay unchanged before its full-resolution frame is drawn: a full frame cannot be
  /// interrupted, so starting one between two mouse events would stall the interaction.
  static constexpr std::chrono::milliseconds kSettle{150};

  /// `renderer` must outlive the worker; `wake` is called (from the worker) when a frame is ready.
  RenderWorker(VolumeRenderer &renderer, std::function<void()> wake);
  ~RenderWorker();

  /// Asks for a frame of `state`; returns its version.
  uint64_t submit(const ViewState &state);
  /// The newest finished frame, if it is newer than the last one taken.
  std::optional<ViewerFrame> take();

private:
  void loop();
  ViewerFrame draw(const ViewState &state, uint64_t version, int scale);
  ViewerFrame drawOrReport(const ViewState &state, uint64_t version, int scale);

  VolumeRenderer &renderer_;
  std::function<void()> wake_;

  std::mutex mutex_;
  std::condition_variable changed_;
  ViewState state_;
  uint64_t version_ = 0;
  std::chrono::steady_clock::time_point submitted_;
  bool stop_ = false;
  std::optional<ViewerFrame> finished_;
  std::thread thread_;
};

} // namespace uvr
