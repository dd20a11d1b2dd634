#include "render/render_defaults.h"

#include "core/error.h"

#include <tbb/info.h>

#include <algorithm>

namespace uvr {

int chooseField(const Mesh &mesh, const std::string &name, const std::string &source) {
  if (mesh.cellCount() == 0)
    throw Error(source, "", "the file holds no volume cells (tetra, hexahedron, wedge or pyramid)");
  if (mesh.fields.empty())
    throw Error(source, "", "the mesh has no scalar field to render");
  if (name.empty())
    return 0;
  const int index = mesh.findField(name);
  if (index < 0) {
    std::string names;
    for (const ScalarField &f : mesh.fields)
      names += (names.empty() ? "" : ", ") + f.name;
    throw Error(source, "", "no field named '" + name + "'; fields: " + names);
  }
  return index;
}

IntegratorSettings samplingSettings(RenderMode mode, float defaultStep, float s1, float s2, float p,
                                    float unit) {
  IntegratorSettings is;
  is.mode = mode;
  is.s1 = s1 > 0.f ? s1 : defaultStep;
  is.s2 = s2 > 0.f ? s2 : std::max(kDefaultS2Factor * defaultStep, is.s1);
  is.p = p > 0.f ? p : kDefaultP;
  is.unit = unit > 0.f ? unit : defaultStep;
  return is;
}

nlohmann::json frameStats(const Mesh &mesh, const Renderer &renderer, const RenderSettings &settings,
                          const Frame &frame, double renderMs, int fieldIndex) {
  const IntegratorSettings &is = settings.integrator;
  const double pixels = double(settings.width) * double(settings.height);
  nlohmann::json stats = {
      {"mode", modeName(is.mode)},
      {"width", settings.width},
      {"height", settings.height},
      {"cells", mesh.cellCount()},
      {"partitions", renderer.partitionCount(settings.backend)},
      {"partitions_skipped", skipsSpace(is.mode) ? renderer.transparentPartitions() : 0},
      {"samples_total", frame.samplesTotal},
      {"samples_per_pixel_mean", double(frame.samplesTotal) / pixels},
      {"samples_per_pixel_max", frame.samplesMax},
      {"build_ms", renderer.buildMs(settings.backend)},
      {"tf_update_ms", renderer.tfUpdateMs()},
      {"render_ms", renderMs},
      {"s1", is.s1},
      {"s2", is.s2},
      {"p", is.p},
      {"unit", is.unit},
      {"leaf_size", renderer.leafSize()},
      {"field", mesh.fields[size_t(fieldIndex)].name},
      {"range", {renderer.transferFunction().valueMin(), renderer.transferFunction().valueMax()}},
      {"backend", backendName(settings.backend)},
      {"threads", tbb::info::default_concurrency()},
  };
  if (settings.backend == Backend::Cuda) {
    stats["device"] = renderer.deviceName();
    stats["gpu_memory_bytes"] = renderer.deviceMemoryBytes();
    stats["gpu_scene_bytes"] = renderer.deviceSceneBytes();
    nlohmann::json steps = nlohmann::json::object();
    for (const auto &[step, ms] : renderer.deviceBuildSteps())
      steps[step] = ms;
    stats["gpu_build_steps_ms"] = steps;
  }
  return stats;
}

} // namespace uvr
