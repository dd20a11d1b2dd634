// What the command, the viewer and the Python module share beyond the library's API: the statistics of a
// frame as `uvr render --stats` writes them, the checks whose messages name the command's options, and
// output files written whole or not at all.
#pragma once

#include <uvr/camera.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <string>

namespace uvr {

/// The keys of `uvr render --stats` but load_ms, time_step, frames and gpu_kernel_ms.
nlohmann::json frameStatsJson(const FrameStats &stats);

/// parseBackend, and an error when this build lacks the backend.
Backend parseBackendOption(const std::string &name);

/// Throws uvr::Error naming `option` unless a file can be created at `path` (its folder exists and is
/// writable, and it is no folder), so that a bad output fails before any work.
void checkOutputPath(const std::string &path, const std::string &option);

/// Calls `write` with a temporary path beside `path` (same extension), then renames it to `path`: the file
/// appears whole or not at all. Throws uvr::Error naming `path` and the reason.
void writeWhole(const std::string &path, const std::function<void(const std::string &)> &write);

} // namespace uvr
