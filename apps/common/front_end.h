// What the command, the viewer and the Python module share beyond the library's API: the statistics of a
// frame as `uvr render --stats` writes them, and the checks whose messages name the command's options.
#pragma once

#include <uvr/camera.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>

#include <nlohmann/json.hpp>

#include <string>

namespace uvr {

/// The keys of `uvr render --stats` but load_ms, time_step, frames and gpu_kernel_ms.
nlohmann::json frameStatsJson(const FrameStats &stats);

/// parseBackend, and an error when this build lacks the backend.
Backend parseBackendOption(const std::string &name);

/// Throws uvr::Error when the camera's view direction and view-up are collinear.
void checkCamera(const Camera &camera);

} // namespace uvr
