#include "commands.h"
#include "option_checks.h"

#include "data_parallel.h"
#include "front_end.h"

#include <uvr/error.h>
#include <uvr/io.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>

namespace uvr {

namespace {

struct ConvertOptions {
  std::string input;
  std::string output;
  std::vector<std::string> fields;
  bool zlib = false;
  int timeStep = 0;
  int pieces = 0; ///< for .pvtu: the pieces to write
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

std::string escapeXml(const std::string &text) {
  std::string escaped;
  for (const char c : text) {
    switch (c) {
    case '&':
      escaped += "&amp;";
      break;
    case '<':
      escaped += "&lt;";
      break;
    case '>':
      escaped += "&gt;";
      break;
    case '"':
      escaped += "&quot;";
      break;
    default:
      escaped += c;
    }
  }
  return escaped;
}

std::string numbers(std::initializer_list<double> values, const char *format = "%.9g") {
  std::string text;
  for (const double v : values) {
    char number[32];
    std::snprintf(number, sizeof number, format, v);
    text += (text.empty() ? "" : " ") + std::string(number);
  }
  return text;
}

std::string boxText(const Box3f &b) {
  return numbers({b.lower.x, b.lower.y, b.lower.z, b.upper.x, b.upper.y, b.upper.z});
}

/// ParaView's partitioned file: OUT.pvtu naming the pieces OUT/OUT_<i>.vtu, the regions of a KD split of the
/// mesh in the split's order (front to back along each split), each cell in the piece whose region owns it,
/// and each piece's region in its <Piece>'s uvr_region attribute (xmin ymin zmin xmax ymax zmax). For the
/// ranks of `mpirun uvr render`, which read only their pieces (readPartitionedFile): each piece's ghost
/// cells, those of other pieces whose boxes reach into its region, in OUT/OUT_<i>_ghosts.vtu (uvr_ghosts;
/// not a piece, so ParaView draws each cell once), and what the ranks take from the whole mesh in uvr_
/// attributes of <PUnstructuredGrid> and each field's uvr_range.
void writePartitioned(const VolumeMesh &mesh, const ConvertOptions &o, const SaveOptions &save) {
  namespace fs = std::filesystem;
  const fs::path output(o.output);
  const std::string stem = output.stem().string();
  const fs::path folder = output.parent_path() / stem;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec)
    throw Error(folder.string(), "", "cannot create the folder of the pieces: " + ec.message());
  const MeshRegions regions = splitIntoRegions(mesh, o.pieces);
  std::string pieces;
  for (int i = 0; i < o.pieces; ++i) {
    const Box3f &region = regions.regions[size_t(i)];
    const std::string name = stem + "_" + std::to_string(i) + ".vtu";
    const VolumeMesh piece = ownedCells(mesh, region);
    writeWhole((folder / name).string(), [&](const std::string &temporary) { piece.save(temporary, save); });
    pieces +=
        "    <Piece Source=\"" + escapeXml(stem + "/" + name) + "\" uvr_region=\"" + boxText(region) + "\"";
    const VolumeMesh ghosts = ghostCells(mesh, region);
    if (ghosts.cellCount() > 0) {
      const std::string ghostName = stem + "_" + std::to_string(i) + "_ghosts.vtu";
      writeWhole((folder / ghostName).string(),
                 [&](const std::string &temporary) { ghosts.save(temporary, save); });
      pieces += " uvr_ghosts=\"" + escapeXml(stem + "/" + ghostName) + "\"";
    }
    pieces += "/>\n";
  }
  std::string point, cell;
  for (int f = 0; f < mesh.fieldCount(); ++f) {
    const FieldInfo field = mesh.field(f);
    const ValueRange range = mesh.fieldRange(f);
    (field.centering == Centering::Point ? point : cell) += "      <PDataArray type=\"Float32\" Name=\"" +
                                                            escapeXml(field.name) + "\" uvr_range=\"" +
                                                            numbers({range.min, range.max}) + "\"/>\n";
  }
  const VolumeMesh::StepScaleReference scales = mesh.stepScaleReference();
  const std::string whole =
      " uvr_cells=\"" + std::to_string(mesh.cellCount()) + "\" uvr_bounds=\"" + boxText(mesh.bounds()) +
      "\" uvr_default_step=\"" + numbers({mesh.defaultStep()}) + "\" uvr_median_volume=\"" +
      numbers({mesh.volumeStats().median}, "%.17g") + "\" uvr_leaf_size=\"" +
      std::to_string(mesh.defaultLeafSize()) + "\" uvr_step_scales=\"" +
      numbers({scales.meanCellSizeLog2}, "%.17g") + " " + numbers({scales.finestStepScale}) + "\"";
  writeWhole(o.output, [&](const std::string &temporary) {
    std::ofstream out(temporary);
    out << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
           "header_type=\"UInt64\">\n"
        << "  <PUnstructuredGrid GhostLevel=\"0\"" << whole << ">\n"
        << "    <PPointData>\n"
        << point << "    </PPointData>\n"
        << "    <PCellData>\n"
        << cell << "    </PCellData>\n"
        << "    <PPoints>\n      <PDataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
        << "    </PPoints>\n"
        << pieces << "  </PUnstructuredGrid>\n</VTKFile>\n";
    out.close();
    if (!out)
      throw Error(o.output, "", std::string("cannot write: ") + std::strerror(errno));
  });
}

void runConvert(const ConvertOptions &o) {
  std::string extension = std::filesystem::path(o.output).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  const bool umesh = extension == ".umesh";
  const bool partitioned = extension == ".pvtu";
  if (!umesh && extension != ".vtu" && !partitioned)
    throw Error(o.output, "", "OUT must end in .vtu, .pvtu or .umesh");
  if (partitioned != (o.pieces > 0))
    throw Error(o.output, "", partitioned ? "a .pvtu needs --pieces N" : "--pieces writes .pvtu only");
  if (o.zlib && umesh)
    throw Error(o.output, "", "--zlib applies to .vtu and .pvtu output only");
  checkOutputPath(o.output, "OUT");
  LoadOptions options;
  options.timeStep = o.timeStep;
  VolumeMesh mesh = chooseFields(VolumeMesh::load(o.input, options), o.fields, o.input);
  if (umesh)
    mesh = dropCellFields(std::move(mesh), o);
  SaveOptions save;
  save.compress = o.zlib;
  if (partitioned) {
    if (mesh.cellCount() < uint64_t(o.pieces))
      throw Error(o.input, "", "--pieces " + std::to_string(o.pieces) + ": more pieces than cells");
    writePartitioned(mesh, o, save);
    std::fprintf(stderr, "uvr: wrote %s: %d pieces, %llu cells, %d fields\n", o.output.c_str(), o.pieces,
                 static_cast<unsigned long long>(mesh.cellCount()), mesh.fieldCount());
    return;
  }
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
  cmd->add_option("OUT", options->output, "Mesh file to write (.vtu, .umesh; .pvtu with --pieces)")
      ->required();
  cmd->add_option("--field", options->fields, "Field to keep (repeat the option for several; default: all)")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--time-step", options->timeStep,
                  "Time step of a series, an Exodus file or a Gmsh file's data, from 0")
      ->check(integerAtLeast(0))
      ->capture_default_str();
  cmd->add_flag("--zlib", options->zlib, "Compress the .vtu arrays with zlib");
  cmd->add_option("--pieces", options->pieces,
                  "Write a partitioned .pvtu of this many pieces, the regions of a KD split of the mesh")
      ->check(integerAtLeast(1));
  cmd->callback([options] { runConvert(*options); });
}

} // namespace uvr
