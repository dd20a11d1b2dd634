#include "commands.h"
#include "option_checks.h"

#include "front_end.h"

#include <uvr/error.h>
#include <uvr/io.h>
#include <uvr/mesh.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace uvr {

namespace {

struct ConvertOptions {
  std::string input;
  std::string output;
  std::vector<std::string> fields;
  bool zlib = false;
  int timeStep = 0;
};

/// The named fields in the order given; all of them when none is named.
VolumeMesh chooseFields(VolumeMesh mesh, const std::vector<std::string> &names, const std::string &path) {
  if (names.empty())
    return mesh;
  std::vector<int> chosen;
  for (const std::string &name : names) {
    const int index = mesh.findField(name);
    if (index < 0) {
      std::string available;
      for (int i = 0; i < mesh.fieldCount(); ++i)
        available += (available.empty() ? "" : ", ") + mesh.field(i).name;
      throw Error(path, "",
                  "--field: no field '" + name +
                      "' (the file has: " + (available.empty() ? "none" : available) + ")");
    }
    chosen.push_back(index);
  }
  return std::move(mesh).withFields(chosen);
}

/// For .umesh, which holds point fields only: the mesh without its cell fields, named in one line on stderr.
/// A cell field named by --field is refused, as is a mesh left with no field.
VolumeMesh dropCellFields(VolumeMesh mesh, const ConvertOptions &o) {
  std::vector<int> kept;
  std::string dropped;
  for (int i = 0; i < mesh.fieldCount(); ++i) {
    const FieldInfo field = mesh.field(i);
    if (field.centering == Centering::Point) {
      kept.push_back(i);
      continue;
    }
    if (!o.fields.empty())
      throw Error(o.output, "",
                  "umesh stores per-vertex scalars only, and '" + field.name +
                      "' is a cell field: choose point fields with --field, or write .vtu");
    dropped += (dropped.empty() ? "'" : ", '") + field.name + "'";
  }
  if (dropped.empty())
    return mesh;
  if (kept.empty())
    throw Error(o.output, "",
                "umesh stores per-vertex scalars only, and every field of " + o.input + " is a cell field (" +
                    dropped + "): write .vtu");
  std::fprintf(stderr, "uvr: %s: dropped cell field(s) %s (.umesh holds point fields only)\n",
               o.output.c_str(), dropped.c_str());
  return std::move(mesh).withFields(kept);
}

void runConvert(const ConvertOptions &o) {
  std::string extension = std::filesystem::path(o.output).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  const bool umesh = extension == ".umesh";
  if (!umesh && extension != ".vtu")
    throw Error(o.output, "", "OUT must end in .vtu or .umesh");
  if (o.zlib && extension != ".vtu")
    throw Error(o.output, "", "--zlib applies to .vtu output only");
  checkOutputPath(o.output, "OUT");
  LoadOptions options;
  options.timeStep = o.timeStep;
  VolumeMesh mesh = chooseFields(VolumeMesh::load(o.input, options), o.fields, o.input);
  if (umesh)
    mesh = dropCellFields(std::move(mesh), o);
  SaveOptions save;
  save.compress = o.zlib;
  writeWhole(o.output, [&](const std::string &temporary) { mesh.save(temporary, save); });
  std::fprintf(stderr, "uvr: wrote %s: %llu points, %llu cells, %d fields\n", o.output.c_str(),
               static_cast<unsigned long long>(mesh.pointCount()),
               static_cast<unsigned long long>(mesh.cellCount()), mesh.fieldCount());
}

} // namespace

void addConvertCommand(CLI::App &app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App *cmd = app.add_subcommand("convert", "Convert a mesh to another format (.vtu, .umesh)");
  cmd->add_option("IN", options->input,
                  "Mesh to read (.vtu, .vtk, .msh, .e, .ex2, .exo, .g, .umesh; a .pvd series or numbered "
                  "files such as data_%d.vtu)")
      ->required();
  cmd->add_option("OUT", options->output, "Mesh file to write (.vtu, .umesh)")->required();
  cmd->add_option("--field", options->fields, "Field to keep (repeat the option for several; default: all)")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--time-step", options->timeStep,
                  "Time step of a series, an Exodus file or a Gmsh file's data, from 0")
      ->check(integerAtLeast(0))
      ->capture_default_str();
  cmd->add_flag("--zlib", options->zlib, "Compress the .vtu arrays with zlib");
  cmd->callback([options] { runConvert(*options); });
}

} // namespace uvr
