#include "render_worker.h"

#include "front_end.h"

#include <algorithm>

namespace uvr {

RenderWorker::RenderWorker(VolumeRenderer &renderer, std::function<void()> wake)
    : renderer_(renderer), wake_(std::move(wake)), thread_([this] { loop(); }) {}

RenderWorker::~RenderWorker() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

uint64_t RenderWorker::submit(const ViewState &state) {
  uint64_t version;
  {
    const std::lock_guard lock(mutex_);
    state_ = state;
    version = ++version_;
    submitted_ = std::chrono::steady_clock::now();
  }
  changed_.notify_all();
  return version;
}

std::optional<ViewerFrame> RenderWorker::take() {
  const std::lock_guard lock(mutex_);
  std::optional<ViewerFrame> frame = std::move(finished_);
  finished_.reset();
  return frame;
}

ViewerFrame RenderWorker::draw(const ViewState &state, uint64_t version, int scale) {
  // Only this thread touches the renderer: a new transfer function recomputes the partitions' metadata alone,
  // and the same one again nothing.
  renderer_.setTransferFunction(state.colorMap, state.range);
  FrameSettings settings = state.settings;
  settings.width = std::max(1, settings.width / scale);
  settings.height = std::max(1, settings.height / scale);
  ViewerFrame result;
  result.scale = scale;
  result.version = version;
  renderer_.prepare(settings.backend);
  result.frame = renderer_.render(state.camera, settings);
  result.stats = frameStatsJson(result.frame.stats);
  return result;
}

ViewerFrame RenderWorker::drawOrReport(const ViewState &state, uint64_t version, int scale) {
  try {
    return draw(state, version, scale);
  } catch (const std::exception &e) {
    ViewerFrame failed;
    failed.scale = scale;
    failed.version = version;
    failed.error = e.what();
    return failed;
  }
}

void RenderWorker::loop() {
  uint64_t drawn = 0;   // version of the last preview or full frame
  bool fullDone = true; // whether `drawn` has its full-resolution frame
  std::unique_lock lock(mutex_);
  while (!stop_) {
    if (version_ != drawn) {
      const ViewState state = state_;
      const uint64_t version = version_;
      lock.unlock();
      ViewerFrame frame = drawOrReport(state, version, kPreviewScale);
      lock.lock();
      finished_ = std::move(frame);
      drawn = version;
      fullDone = false;
      wake_();
    } else if (!fullDone) {
      const auto due = submitted_ + kSettle;
      if (std::chrono::steady_clock::now() < due) {
        changed_.wait_until(lock, due);
        continue;
      }
      const ViewState state = state_;
      lock.unlock();
      ViewerFrame frame = drawOrReport(state, drawn, 1);
      lock.lock();
      // A view submitted meanwhile supersedes this frame; its preview comes next.
      if (version_ == drawn)
        finished_ = std::move(frame);
      fullDone = true;
      wake_();
    } else {
      changed_.wait(lock);
    }
  }
}

} // namespace uvr
