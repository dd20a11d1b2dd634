// What `uvr render`, the viewer and the Python module choose when the user leaves a setting out, in one place
// so that the same view renders the same image from each of them.
#pragma once

#include "mesh/mesh.h"
#include "render/camera.h"
#include "render/color_map.h"
#include "render/renderer.h"

#include <nlohmann/json.hpp>

#include <string>

namespace uvr {

/// Defaults measured on the brain meshes (README, "Choosing defaults"): s2 = kDefaultS2Factor * s1.
constexpr float kDefaultS2Factor = 8.f;
constexpr float kDefaultP = 4.f;

/// Checks that `mesh` holds volume cells and a scalar field, and returns the index of the field `name` (the
/// first field when empty). Errors name `source` and list the fields.
int chooseField(const Mesh &mesh, const std::string &name, const std::string &source);

/// Sampling settings with the defaults for what is not given (<= 0): s1 and unit = `defaultStep` (see
/// defaultStepSize), s2 = kDefaultS2Factor * defaultStep (at least s1), p = kDefaultP.
IntegratorSettings samplingSettings(RenderMode mode, float defaultStep, float s1 = 0.f, float s2 = 0.f,
                                    float p = 0.f, float unit = 0.f);

/// The statistics of one frame under the keys of `uvr render --stats` (all but load_ms and frames).
nlohmann::json frameStats(const Mesh &mesh, const Renderer &renderer, const RenderSettings &settings,
                          const Frame &frame, double renderMs, int fieldIndex);

} // namespace uvr
