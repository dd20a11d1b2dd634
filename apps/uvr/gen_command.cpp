#include "commands.h"
#include "option_checks.h"

#include "front_end.h"

#include <uvr/error.h>
#include <uvr/gen.h>
#include <uvr/mesh.h>
#include <uvr/system.h>

#include <cstdio>
#include <map>
#include <memory>
#include <optional>

namespace uvr {

namespace {

struct GenCommandOptions {
  std::string volume;
  std::string output;
  uint64_t cells = 1000000;
  std::optional<float> threshold;
  std::string cellType = "tet";
  uint64_t seed = 0;
  bool cellField = false;
  std::vector<int64_t> dims;
  std::string type;
  std::vector<double> spacing{1.0, 1.0, 1.0};
};

VoxelVolume readVolume(const GenCommandOptions &o) {
  if (o.dims.empty()) {
    if (!o.type.empty())
      throw Error(o.volume, "", "--type applies to raw volumes, which need --dims");
    return VoxelVolume::readNifti(o.volume);
  }
  static const std::map<std::string, VoxelType> types = {{"uint8", VoxelType::UInt8},
                                                         {"int16", VoxelType::Int16},
                                                         {"uint16", VoxelType::UInt16},
                                                         {"float32", VoxelType::Float32}};
  const auto type = types.find(o.type);
  if (type == types.end())
    throw Error(o.volume, "", "a raw volume needs --type uint8, int16, uint16 or float32");
  for (int a = 0; a < 3; ++a) {
    if (o.dims[size_t(a)] < 1)
      throw Error(o.volume, "", "expected positive --dims");
    if (!(o.spacing[size_t(a)] > 0))
      throw Error(o.volume, "", "expected positive --spacing");
  }
  return VoxelVolume::readRaw(o.volume, {o.dims[0], o.dims[1], o.dims[2]}, type->second,
                              {o.spacing[0], o.spacing[1], o.spacing[2]});
}

void runGen(const GenCommandOptions &o) {
  if (!o.output.ends_with(".umesh") && !o.output.ends_with(".vtu"))
    throw Error(o.output, "", "expected an output file ending in .umesh or .vtu");
  checkOutputPath(o.output, "-o");
  Timer loadTimer;
  const VoxelVolume volume = readVolume(o);
  const double loadMs = loadTimer.milliseconds();

  GenOptions options;
  options.cells = o.cells;
  options.threshold = o.threshold;
  options.seed = o.seed;
  options.cellField = o.cellField;
  const float threshold = volume.threshold(options);
  options.threshold = threshold;
  Timer genTimer;
  const VolumeMesh mesh =
      volume.generateMesh(options, o.cellType == "hex" ? CellType::Hexahedron : CellType::Tetra);
  const double genMs = genTimer.milliseconds();
  Timer saveTimer;
  writeWhole(o.output, [&](const std::string &temporary) { mesh.save(temporary); });
  const double saveMs = saveTimer.milliseconds();

  std::fprintf(stderr,
               "uvr gen: %s: %llu %s, %llu points, field '%s'%s; threshold %g%s\n"
               "  read %.0f ms, generated in %.0f ms (%.2f M cells/s on %d threads), written in %.0f ms\n",
               o.output.c_str(), static_cast<unsigned long long>(mesh.cellCount()),
               o.cellType == "hex" ? "hexahedra" : "tetrahedra",
               static_cast<unsigned long long>(mesh.pointCount()), volume.name().c_str(),
               o.cellField ? (" and '" + volume.name() + "_cell'").c_str() : "", threshold,
               o.threshold ? "" : " (Otsu)", loadMs, genMs, double(mesh.cellCount()) / genMs * 1e-3,
               threadCount(), saveMs);
}

} // namespace

void addGenCommand(CLI::App &app) {
  auto options = std::make_shared<GenCommandOptions>();
  CLI::App *cmd = app.add_subcommand(
      "gen",
      "Mesh the part of a structured volume that passes a threshold: graded, conforming tets or hexes");
  cmd->add_option("VOLUME", options->volume, "NIfTI-1 volume (.nii, .nii.gz), or a raw file with --dims")
      ->required();
  cmd->add_option("--cells", options->cells, "Target cell count (met within 10 %)")
      ->check(CLI::Range(uint64_t(1000), uint64_t(4000000000ull)));
  cmd->add_option("--threshold", options->threshold,
                  "Keep cells whose centroid value is >= this (default: Otsu's threshold of the volume)")
      ->check(finiteNumber());
  cmd->add_option("--cell-type", options->cellType, "tet (default) or hex")
      ->check(CLI::IsMember({"tet", "hex"}));
  cmd->add_option("--seed", options->seed, "Seed of the vertex jitter (default 0)")->check(integerAtLeast(0));
  cmd->add_flag("--cell-field", options->cellField,
                "Also store the value at each cell's centroid as '<name>_cell' (.vtu only)");
  cmd->add_option("--dims", options->dims, "Raw volume: voxels per axis X,Y,Z")
      ->delimiter(',')
      ->expected(3)
      ->check(integerAtLeast(1));
  cmd->add_option("--type", options->type, "Raw volume: uint8, int16, uint16 or float32 (little-endian)");
  cmd->add_option("--spacing", options->spacing, "Raw volume: voxel spacing X,Y,Z (default 1,1,1)")
      ->delimiter(',')
      ->expected(3)
      ->check(positiveNumber());
  cmd->add_option("-o,--output", options->output, "Mesh file to write (.umesh, .vtu)")->required();
  cmd->callback([options] { runGen(*options); });
}

} // namespace uvr
