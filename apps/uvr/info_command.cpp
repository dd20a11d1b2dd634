#include "commands.h"
#include "option_checks.h"

#include <uvr/io.h>
#include <uvr/mesh.h>
#include <uvr/system.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>

namespace uvr {

namespace {

struct InfoOptions {
  std::string mesh;
  bool json = false;
  int timeStep = 0;
};

/// CPU time of all the process's threads: on a busy machine, the work a load takes apart from waiting.
double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

void runInfo(const InfoOptions &o) {
  const Timer loadTimer;
  const double cpuBefore = processCpuMs();
  LoadOptions options;
  options.timeStep = o.timeStep;
  const VolumeMesh mesh = VolumeMesh::load(o.mesh, options);
  const double loadMs = loadTimer.milliseconds();
  const double loadCpuMs = processCpuMs() - cpuBefore;
  const int timeSteps = timeStepCount(o.mesh);
  const VolumeStats volumes = mesh.volumeStats();
  const Box3f bounds = mesh.bounds();
  const CellCounts cells = mesh.cellCounts();
  const uint32_t partitions = mesh.partitionCount();

  nlohmann::json fields = nlohmann::json::array();
  for (int i = 0; i < mesh.fieldCount(); ++i) {
    const FieldInfo field = mesh.field(i);
    const ValueRange range = mesh.fieldRange(i);
    fields.push_back({{"name", field.name},
                      {"centering", field.centering == Centering::Point ? "point" : "cell"},
                      {"min", range.min},
                      {"max", range.max}});
  }
  nlohmann::json info = {
      {"points", mesh.pointCount()},
      {"cells", mesh.cellCount()},
      {"cell_types",
       {{"tet", cells.tet},
        {"hex", cells.hex},
        {"wedge", cells.wedge},
        {"pyramid", cells.pyramid},
        {"skipped", cells.skipped}}},
      {"fields", fields},
      {"bounds",
       {bounds.lower.x, bounds.upper.x, bounds.lower.y, bounds.upper.y, bounds.lower.z, bounds.upper.z}},
      {"inverted_cells", cells.inverted},
      {"polyhedra",
       {{"polyhedron", cells.polyhedron},
        {"tet", cells.polyhedronTets},
        {"pyramid", cells.polyhedronPyramids}}},
      {"volume_min", volumes.min},
      {"volume_median", volumes.median},
      {"volume_max", volumes.max},
      {"volume_p1", volumes.p1},
      {"volume_p99", volumes.p99},
      {"volume_ratio", volumes.min > 0 ? nlohmann::json(volumes.max / volumes.min) : nlohmann::json(nullptr)},
      {"volume_ratio_p99_p1",
       volumes.p1 > 0 ? nlohmann::json(volumes.p99 / volumes.p1) : nlohmann::json(nullptr)},
      {"partitions", partitions},
      {"time_steps", timeSteps},
      {"time_step", o.timeStep},
      {"load_ms", loadMs},
      {"load_cpu_ms", loadCpuMs},
  };
  if (o.json) {
    std::printf("%s\n", info.dump(2).c_str());
    return;
  }
  std::printf("%s\n", o.mesh.c_str());
  std::printf("  points          %llu\n", static_cast<unsigned long long>(mesh.pointCount()));
  std::printf("  cells           %llu (tet %llu, hex %llu, wedge %llu, pyramid %llu; skipped %llu "
              "lower-dimensional)\n",
              static_cast<unsigned long long>(mesh.cellCount()), static_cast<unsigned long long>(cells.tet),
              static_cast<unsigned long long>(cells.hex), static_cast<unsigned long long>(cells.wedge),
              static_cast<unsigned long long>(cells.pyramid), static_cast<unsigned long long>(cells.skipped));
  if (cells.polyhedron > 0)
    std::printf("  polyhedron      %llu (decomposed into %llu tetrahedra, %llu pyramids)\n",
                static_cast<unsigned long long>(cells.polyhedron),
                static_cast<unsigned long long>(cells.polyhedronTets),
                static_cast<unsigned long long>(cells.polyhedronPyramids));
  for (int i = 0; i < mesh.fieldCount(); ++i) {
    const FieldInfo field = mesh.field(i);
    const ValueRange range = mesh.fieldRange(i);
    std::printf("  field           %s (%s) [%g, %g]\n", field.name.c_str(),
                field.centering == Centering::Point ? "point" : "cell", range.min, range.max);
  }
  std::printf("  bounds          [%g, %g] x [%g, %g] x [%g, %g]\n", bounds.lower.x, bounds.upper.x,
              bounds.lower.y, bounds.upper.y, bounds.lower.z, bounds.upper.z);
  std::printf("  inverted cells  %llu\n", static_cast<unsigned long long>(cells.inverted));
  std::printf("  cell volume     min %g, median %g, max %g\n", volumes.min, volumes.median, volumes.max);
  std::printf("  volume spread   max/min %g, p99/p1 %g (p1 %g, p99 %g)\n",
              volumes.min > 0 ? volumes.max / volumes.min : INFINITY,
              volumes.p1 > 0 ? volumes.p99 / volumes.p1 : INFINITY, volumes.p1, volumes.p99);
  std::printf("  partitions      %u (leaf size %u)\n", partitions, mesh.defaultLeafSize());
  std::printf("  time steps      %d (showing %d)\n", timeSteps, o.timeStep);
  std::printf("  load            %.1f ms (cpu %.1f ms)\n", loadMs, loadCpuMs);
}

} // namespace

void addInfoCommand(CLI::App &app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App *cmd =
      app.add_subcommand("info", "Describe a mesh: cells, fields, bounds, cell volumes, partitions");
  cmd->add_option("MESH", options->mesh,
                  "Mesh file (.vtu, .vtk, .msh, .e, .ex2, .exo, .g, .umesh; a .pvd series or numbered files "
                  "such as data_%d.vtu)")
      ->required();
  cmd->add_flag("--json", options->json, "Print JSON");
  cmd->add_option("--time-step", options->timeStep,
                  "Time step of a series, an Exodus file or a Gmsh file's data, from 0")
      ->check(integerAtLeast(0))
      ->capture_default_str();
  cmd->callback([options] { runInfo(*options); });
}

} // namespace uvr
