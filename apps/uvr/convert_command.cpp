#include "commands.h"

#include <uvr/error.h>
#include <uvr/io.h>
#include <uvr/mesh.h>

#include <cstdio>
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
                  "no field '" + name + "' (the file has: " + (available.empty() ? "none" : available) + ")");
    }
    chosen.push_back(index);
  }
  return std::move(mesh).withFields(chosen);
}

void runConvert(const ConvertOptions &o) {
  LoadOptions options;
  options.timeStep = o.timeStep;
  const VolumeMesh mesh = chooseFields(VolumeMesh::load(o.input, options), o.fields, o.input);
  if (o.zlib && !o.output.ends_with(".vtu") && !o.output.ends_with(".VTU"))
    throw Error(o.output, "", "--zlib applies to .vtu output only");
  if (o.output.ends_with(".umesh"))
    for (int i = 0; i < mesh.fieldCount(); ++i)
      if (mesh.field(i).centering == Centering::Cell)
        throw Error(o.output, "",
                    "umesh stores per-vertex scalars only, and '" + mesh.field(i).name +
                        "' is a cell field: choose point fields with --field, or write .vtu");
  SaveOptions save;
  save.compress = o.zlib;
  mesh.save(o.output, save);
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
      ->capture_default_str();
  cmd->add_flag("--zlib", options->zlib, "Compress the .vtu arrays with zlib");
  cmd->callback([options] { runConvert(*options); });
}

} // namespace uvr
