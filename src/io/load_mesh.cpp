#include "core/limits.h"
#include "io/file_buffer.h"
#include "io/glob.h"
#include "io/mesh_io.h"
#include "io/text_scan.h"
#include <uvr/error.h>
#include <uvr/mesh.h>

#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <set>

namespace uvr {

namespace {

namespace fs = std::filesystem;

std::string lowerCaseExtension(const std::string &path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
    return "";
  return toLower(std::string_view(path).substr(dot));
}

bool isExodus(const std::string &extension) {
  return extension == ".e" || extension == ".ex2" || extension == ".exo" || extension == ".g";
}

/// Reads `path` into `file` and parses it in place into `doc`, whose nodes point into `file`. Through
/// readFile, which refuses what is not a regular file (a FIFO) before blocking on it.
void parseXmlFile(const std::string &path, FileBuffer &file, pugi::xml_document &doc) {
  file = readFile(path);
  const pugi::xml_parse_result result = doc.load_buffer_inplace(file.data.data(), file.size);
  if (!result)
    throw Error(path, "byte " + std::to_string(std::max<ptrdiff_t>(result.offset, 0)),
                std::string("malformed XML: ") + result.description());
}

/// The files of each time step of a series, in time order; empty when `path` is a single file.
using Series = std::vector<std::vector<std::string>>;

Series readPvd(const std::string &path) {
  FileBuffer file;
  pugi::xml_document doc;
  parseXmlFile(path, file, doc);
  const pugi::xml_node collection = doc.child("VTKFile").child("Collection");
  if (std::string_view(doc.child("VTKFile").attribute("type").value()) != "Collection" || !collection)
    throw Error(path, "", "expected <VTKFile type=\"Collection\"> with a <Collection>");
  struct DataSet {
    double time;
    std::string file;
  };
  std::vector<DataSet> dataSets;
  const fs::path directory = fs::path(path).parent_path();
  for (pugi::xml_node node : collection.children("DataSet")) {
    const std::string file = node.attribute("file").value();
    const std::string position = "byte " + std::to_string(node.offset_debug());
    if (file.empty())
      throw Error(path, position, "<DataSet> without a file attribute");
    // A collection names mesh files only: no nesting, so no recursion and no cycle (a .pvd naming itself).
    if (lowerCaseExtension(file) == ".pvd")
      throw Error(path, position,
                  "<DataSet> names another collection '" + quoteInput(file) + "': it must name a mesh file");
    dataSets.push_back({node.attribute("timestep").as_double(0.0),
                        fs::path(file).is_absolute() ? file : (directory / file).string()});
  }
  if (dataSets.empty())
    throw Error(path, "", "the collection lists no <DataSet>");
  std::stable_sort(dataSets.begin(), dataSets.end(),
                   [](const DataSet &a, const DataSet &b) { return a.time < b.time; });
  Series series;
  std::set<std::string> stepFiles; // a file twice in one step would be merged with itself
  for (size_t i = 0; i < dataSets.size(); ++i) {
    if (i == 0 || dataSets[i].time != dataSets[i - 1].time) {
      series.emplace_back();
      stepFiles.clear();
    }
    if (!stepFiles.insert(fs::path(dataSets[i].file).lexically_normal().string()).second)
      throw Error(path, "",
                  "time step " + std::to_string(series.size() - 1) + " names '" +
                      quoteInput(dataSets[i].file) + "' more than once");
    series.back().push_back(dataSets[i].file);
  }
  return series;
}

/// Numbers of a uvr_ attribute, space-separated; empty where absent.
std::vector<double> numbersOf(const pugi::xml_node &node, const char *name) {
  std::vector<double> numbers;
  const char *text = node.attribute(name).value();
  for (char *end = nullptr;; text = end) {
    const double value = std::strtod(text, &end);
    if (end == text)
      break;
    numbers.push_back(value);
  }
  return numbers;
}

Box3f boxOf(const std::vector<double> &v) {
  if (v.size() != 6)
    return {};
  return {{float(v[0]), float(v[1]), float(v[2])}, {float(v[3]), float(v[4]), float(v[5])}};
}

/// A ParaView partitioned file (.pvtu): its pieces in order, with what `uvr convert --pieces` adds.
PartitionedFile parsePvtu(const std::string &path) {
  FileBuffer file;
  pugi::xml_document doc;
  parseXmlFile(path, file, doc);
  const pugi::xml_node grid = doc.child("VTKFile").child("PUnstructuredGrid");
  if (std::string_view(doc.child("VTKFile").attribute("type").value()) != "PUnstructuredGrid" || !grid)
    throw Error(path, "", "expected <VTKFile type=\"PUnstructuredGrid\"> with a <PUnstructuredGrid>");
  PartitionedFile parts;
  const fs::path directory = fs::path(path).parent_path();
  const auto near = [&](const std::string &source) {
    return fs::path(source).is_absolute() ? source : (directory / source).string();
  };
  for (pugi::xml_node node : grid.children("Piece")) {
    const std::string source = node.attribute("Source").value();
    const std::string position = "byte " + std::to_string(node.offset_debug());
    if (source.empty())
      throw Error(path, position, "<Piece> without a Source attribute");
    if (lowerCaseExtension(source) != ".vtu")
      throw Error(path, position, "<Piece> names '" + quoteInput(source) + "': expected a .vtu file");
    const std::string ghosts = node.attribute("uvr_ghosts").value();
    parts.pieces.push_back(
        {near(source), ghosts.empty() ? ghosts : near(ghosts), boxOf(numbersOf(node, "uvr_region"))});
  }
  if (parts.pieces.empty())
    throw Error(path, "", "the file lists no <Piece>");
  const std::vector<double> cells = numbersOf(grid, "uvr_cells"), step = numbersOf(grid, "uvr_default_step"),
                            median = numbersOf(grid, "uvr_median_volume"),
                            leaf = numbersOf(grid, "uvr_leaf_size"),
                            scales = numbersOf(grid, "uvr_step_scales");
  if (cells.size() == 1 && step.size() == 1 && median.size() == 1 && leaf.size() == 1 && scales.size() == 2) {
    parts.cells = uint64_t(cells[0]);
    parts.bounds = boxOf(numbersOf(grid, "uvr_bounds"));
    parts.defaultStep = float(step[0]);
    parts.medianVolume = median[0];
    parts.leafSize = uint32_t(leaf[0]);
    parts.stepScales = {scales[0], float(scales[1])};
    for (const auto &[data, centering] :
         {std::pair{"PPointData", Centering::Point}, {"PCellData", Centering::Cell}})
      for (pugi::xml_node array : grid.child(data).children("PDataArray")) {
        const std::vector<double> range = numbersOf(array, "uvr_range");
        if (range.size() == 2)
          parts.fieldRanges.push_back(
              {{array.attribute("Name").value(), centering}, {float(range[0]), float(range[1])}});
      }
  }
  return parts;
}

/// The pieces a ParaView partitioned file (.pvtu) names, in its order.
std::vector<std::string> readPvtu(const std::string &path) {
  std::vector<std::string> pieces;
  for (const PartitionedFile::Piece &piece : parsePvtu(path).pieces)
    pieces.push_back(piece.path);
  return pieces;
}

/// Compares names by their text, and embedded numbers by value: data_2 before data_10.
bool naturalLess(const std::string &a, const std::string &b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t iEnd = i, jEnd = j;
      while (iEnd < a.size() && std::isdigit(static_cast<unsigned char>(a[iEnd])))
        ++iEnd;
      while (jEnd < b.size() && std::isdigit(static_cast<unsigned char>(b[jEnd])))
        ++jEnd;
      const std::string_view x = std::string_view(a).substr(i, iEnd - i),
                             y = std::string_view(b).substr(j, jEnd - j);
      const std::string_view xs = x.substr(std::min(x.find_first_not_of('0'), x.size()));
      const std::string_view ys = y.substr(std::min(y.find_first_not_of('0'), y.size()));
      if (xs.size() != ys.size())
        return xs.size() < ys.size();
      if (xs != ys)
        return xs < ys;
      i = iEnd;
      j = jEnd;
    } else {
      if (a[i] != b[j])
        return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

/// Files matching a name pattern with %d, %0Nd, * or ?: a series of one file per step.
Series readPattern(const std::string &path) {
  const fs::path pattern(path);
  const NamePattern matcher(pattern.filename().string());
  const fs::path directory = pattern.has_parent_path() ? pattern.parent_path() : fs::path(".");
  std::error_code ec;
  std::vector<std::string> names;
  std::error_code entryError; // an entry that cannot be examined is no match
  for (const fs::directory_entry &entry : fs::directory_iterator(directory, ec))
    if (entry.is_regular_file(entryError) && matcher.matches(entry.path().filename().string()))
      names.push_back(entry.path().filename().string());
  if (ec)
    throw Error(path, "", "cannot list " + directory.string() + ": " + ec.message());
  if (names.empty())
    throw Error(path, "", "no file matches this pattern");
  std::sort(names.begin(), names.end(), naturalLess);
  Series series;
  for (const std::string &file : names)
    series.push_back({(pattern.has_parent_path() ? (directory / file) : fs::path(file)).string()});
  return series;
}

Series seriesOf(const std::string &path) {
  if (lowerCaseExtension(path) == ".pvd")
    return readPvd(path);
  const std::string name = fs::path(path).filename().string();
  std::error_code ec;
  if (name.find_first_of("*?%") != std::string::npos && !fs::exists(path, ec))
    return readPattern(path);
  return {};
}

/// `alone`: the file is read by itself, where .umesh and .pvd are accepted too (by loadMesh).
UnstructuredGrid readGrid(const std::string &path, const LoadOptions &options, int *steps = nullptr,
                          bool alone = true) {
  const std::string extension = lowerCaseExtension(path);
  if (extension == ".vtu")
    return readVtu(path);
  if (extension == ".vtk")
    return readVtkLegacy(path);
  if (extension == ".msh")
    return readGmsh(path, options, steps);
  if (isExodus(extension))
    return readExodus(path, options.timeStep);
  if (!alone && (extension == ".umesh" || extension == ".pvd"))
    throw Error(
        path, "",
        "a " + extension +
            " file cannot be one of several parts of a time step: expected .vtu, .vtk, .msh, .e, .ex2, "
            ".exo or .g");
  throw Error(path, "",
              "unknown mesh format '" + quoteInput(extension) +
                  "': expected .vtu, .vtk, .msh, .e, .ex2, .exo, " +
                  (alone ? ".g, .umesh or .pvd" : "or .g"));
}

/// Concatenates the parts of one time step: point indices of later parts are shifted past earlier ones.
UnstructuredGrid mergeParts(const std::vector<std::string> &files, const std::string &collection) {
  UnstructuredGrid all = readGrid(files[0], {}, nullptr, false);
  uint64_t bytes = 0;
  for (size_t f = 1; f < files.size(); ++f) {
    UnstructuredGrid part = readGrid(files[f], {}, nullptr, false);
    // Each part is bounded by its own file; together they are bounded by the memory limit.
    bytes += part.points.size() * sizeof(Vec3f) + part.offsets.size() * sizeof(int64_t) +
             part.connectivity.size() * sizeof(int64_t) + part.types.size();
    for (const ScalarField &field : part.fields)
      bytes += field.values.size() * sizeof(float);
    checkMemoryLimit(collection, "", 2 * bytes, "merging its first " + std::to_string(f + 1) + " parts");
    bool sameFields = part.fields.size() == all.fields.size();
    for (size_t i = 0; sameFields && i < all.fields.size(); ++i)
      sameFields =
          part.fields[i].name == all.fields[i].name && part.fields[i].centering == all.fields[i].centering;
    if (!sameFields)
      throw Error(files[f], "", "this part has other fields than " + files[0]);
    const auto pointBase = int64_t(all.points.size());
    const int64_t connectivityBase = all.offsets.back();
    all.points.insert(all.points.end(), part.points.begin(), part.points.end());
    for (size_t i = 1; i < part.offsets.size(); ++i)
      all.offsets.push_back(part.offsets[i] + connectivityBase);
    for (int64_t index : part.connectivity)
      all.connectivity.push_back(index + pointBase);
    all.types.insert(all.types.end(), part.types.begin(), part.types.end());
    all.polyhedra.polyhedra += part.polyhedra.polyhedra;
    all.polyhedra.tets += part.polyhedra.tets;
    all.polyhedra.pyramids += part.polyhedra.pyramids;
    for (size_t i = 0; i < all.fields.size(); ++i)
      all.fields[i].values.insert(all.fields[i].values.end(), part.fields[i].values.begin(),
                                  part.fields[i].values.end());
  }
  return all;
}

Mesh loadSingle(const std::string &path, const LoadOptions &options);

} // namespace

Mesh loadMesh(const std::string &path, const LoadOptions &options) {
  if (lowerCaseExtension(path) == ".pvtu") {
    if (options.timeStep != 0)
      throw Error(path, "", "time step " + std::to_string(options.timeStep) + " asked, the file has 1");
    // The union of the pieces, as one mesh.
    const std::vector<std::string> pieces = readPvtu(path);
    return pieces.size() == 1 ? loadSingle(pieces[0], {}) : buildMesh(mergeParts(pieces, path), path);
  }
  const Series series = seriesOf(path);
  if (!series.empty()) {
    if (options.timeStep < 0 || size_t(options.timeStep) >= series.size())
      throw Error(path, "",
                  "time step " + std::to_string(options.timeStep) + " asked, the series has " +
                      std::to_string(series.size()) + " (0 to " + std::to_string(series.size() - 1) + ")");
    const std::vector<std::string> &files = series[size_t(options.timeStep)];
    // A series' files are read as single files: their names are no patterns, and no collections.
    if (files.size() == 1)
      return loadSingle(files[0], {});
    return buildMesh(mergeParts(files, path), path);
  }
  return loadSingle(path, options);
}

namespace {

Mesh loadSingle(const std::string &path, const LoadOptions &options) {
  if (lowerCaseExtension(path) == ".pvd")
    throw Error(path, "", "a series of files cannot hold a collection (.pvd)");
  if (lowerCaseExtension(path) == ".umesh") {
    if (options.timeStep != 0)
      throw Error(path, "", "time step " + std::to_string(options.timeStep) + " asked, the file has 1");
    return readUmesh(path);
  }
  const std::string extension = lowerCaseExtension(path);
  if (options.timeStep != 0 && extension != ".msh" && !isExodus(extension))
    throw Error(path, "", "time step " + std::to_string(options.timeStep) + " asked, the file has 1");
  if (extension == ".vtu")
    return loadVtu(path);
  return buildMesh(readGrid(path, options), path);
}

} // namespace

PartitionedFile readPartitionedFile(const std::string &path) {
  if (lowerCaseExtension(path) != ".pvtu")
    throw Error(path, "", "not a partitioned file (.pvtu)");
  return parsePvtu(path);
}

int timeStepCount(const std::string &path) {
  const Series series = seriesOf(path);
  if (!series.empty())
    return int(series.size());
  if (lowerCaseExtension(path) == ".msh") {
    int steps = 1;
    readGmsh(path, {}, &steps);
    return steps;
  }
  if (isExodus(lowerCaseExtension(path)))
    return exodusTimeStepCount(path);
  return 1;
}

void saveMesh(const std::string &path, const Mesh &mesh) {
  const std::string extension = lowerCaseExtension(path);
  if (extension == ".umesh")
    return writeUmesh(path, mesh);
  if (extension == ".vtu")
    return writeVtu(path, mesh);
  throw Error(path, "", "cannot write mesh format '" + extension + "': expected .umesh or .vtu");
}

} // namespace uvr
