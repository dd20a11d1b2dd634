// Exodus II (.e, .ex2, .exo, .g) reader through libnetcdf: netCDF-3 and netCDF-4 files.
//
// Every element block of a volume type becomes cells (higher-order ones by their corners, which Exodus lists
// first, as VTK does), NFACED blocks (polyhedra over NSIDED face blocks) decomposed as .vtu polyhedra are;
// other blocks are skipped. Nodal variables become point fields and element variables,
// stored per block, become one cell field over all kept blocks (NaN in blocks that lack the variable).
#include "core/limits.h"
#include "io/mesh_io.h"
#include <uvr/error.h>

#include <string>

#if UVR_HAVE_NETCDF

#include "io/text_scan.h"
#include "mesh/polyhedra.h"

#include <netcdf.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <string_view>
#include <sys/stat.h>
#include <vector>

namespace uvr {

namespace {

/// An Exodus element type name without its node-count suffix ("HEX27" -> "HEX"), upper case.
std::string baseTypeName(const std::string &type) {
  std::string name = toUpper(type);
  while (!name.empty() && (std::isdigit(static_cast<unsigned char>(name.back())) || name.back() == ' '))
    name.pop_back();
  return name;
}

/// The VTK type of an Exodus volume element family, and its corner count; false for other families.
bool volumeType(const std::string &base, uint8_t &vtkType, int &corners) {
  struct Family {
    const char *name;
    uint8_t vtkType;
    int corners;
  };
  static constexpr Family families[] = {
      {"TETRA", 10, 4}, {"TET", 10, 4},     {"HEX", 12, 8},  {"HEXAHEDRON", 12, 8},
      {"WEDGE", 13, 6}, {"PYRAMID", 14, 5}, {"PYRA", 14, 5},
  };
  for (const Family &f : families)
    if (base == f.name) {
      vtkType = f.vtkType;
      corners = f.corners;
      return true;
    }
  return false;
}

/// The end of the data a netCDF-3 (CDF-1, -2 or -5) header lays out, parsed here because netCDF reads zeros
/// past the end of a truncated file instead of failing. Returns nullopt when the header is malformed (netCDF
/// then judges the file).
class ClassicHeader {
public:
  static std::optional<uint64_t> dataEnd(const std::string &path, uint64_t fileSize) {
    // Read a growing prefix until the header fits in it.
    for (uint64_t size = std::min<uint64_t>(fileSize, 1 << 16);; size = std::min(fileSize, size * 4)) {
      ClassicHeader header;
      header.bytes_.resize(size);
      std::ifstream in(path, std::ios::binary);
      if (!in.read(header.bytes_.data(), std::streamsize(size)))
        return std::nullopt;
      header.parse();
      if (!header.needMore_ || size == fileSize)
        return header.ok_ ? std::optional<uint64_t>(header.end_) : std::nullopt;
    }
  }

private:
  uint64_t take(int n) {
    if (!ok_ || pos_ + uint64_t(n) > bytes_.size()) {
      needMore_ = ok_;
      ok_ = false;
      return 0;
    }
    uint64_t value = 0;
    for (int i = 0; i < n; ++i)
      value = value << 8 | uint8_t(bytes_[pos_++]);
    return value;
  }
  uint64_t count() { return take(version_ == 5 ? 8 : 4); }
  void skip(uint64_t n) {
    if (!ok_ || n > bytes_.size() - pos_) {
      needMore_ = ok_;
      ok_ = false;
      return;
    }
    pos_ += n;
  }
  static uint64_t padded(uint64_t n) { return (n + 3) / 4 * 4; }
  static int typeSize(uint64_t type) {
    static constexpr int sizes[] = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8}; // NC_BYTE .. NC_UINT64
    return type >= 1 && type <= 11 ? sizes[type] : 0;
  }
  void name() { skip(padded(count())); }
  /// A list's tag and length; false (and no error) for an absent list.
  bool list(uint64_t tag, uint64_t &n) {
    uint64_t found = take(4);
    n = count();
    if (found == 0 && n == 0)
      return false;
    if (found != tag)
      ok_ = false;
    return ok_;
  }
  void attributes() {
    uint64_t n = 0;
    if (!list(0x0C, n))
      return;
    for (uint64_t i = 0; i < n && ok_; ++i) {
      name();
      int size = typeSize(take(4));
      uint64_t values = count(), bytes = 0;
      if (size == 0 || __builtin_mul_overflow(values, uint64_t(size), &bytes))
        ok_ = false;
      skip(padded(bytes));
    }
  }

  void parse() {
    if (take(3) != 0x434446) // "CDF"
      ok_ = false;
    version_ = int(take(1));
    if (version_ != 1 && version_ != 2 && version_ != 5)
      ok_ = false;
    uint64_t records = count();
    if (records == (version_ == 5 ? UINT64_MAX : UINT32_MAX))
      records = 0; // streaming: the record count follows from the file size
    std::vector<uint64_t> dims;
    uint64_t n = 0;
    if (list(0x0A, n))
      for (uint64_t i = 0; i < n && ok_; ++i) {
        name();
        dims.push_back(count());
      }
    attributes();
    struct Var {
      uint64_t bytes, begin;
      bool record;
    };
    std::vector<Var> vars;
    uint64_t recordSize = 0;
    if (list(0x0B, n))
      for (uint64_t i = 0; i < n && ok_; ++i) {
        name();
        uint64_t rank = count(), bytes = 1;
        bool record = false;
        for (uint64_t d = 0; d < rank && ok_; ++d) {
          uint64_t id = count();
          if (id >= dims.size())
            ok_ = false;
          else if (dims[id] == 0 && d == 0)
            record = true;
          else if (__builtin_mul_overflow(bytes, dims[id], &bytes))
            ok_ = false;
        }
        attributes();
        int size = typeSize(take(4));
        count(); // vsize: recomputed from the shape, as it saturates for large variables
        uint64_t begin = take(version_ == 1 ? 4 : 8);
        if (size == 0 || __builtin_mul_overflow(bytes, uint64_t(size), &bytes))
          ok_ = false;
        vars.push_back({bytes, begin, record});
        if (record)
          recordSize += padded(bytes);
      }
    if (!ok_)
      return;
    size_t recordVars =
        size_t(std::count_if(vars.begin(), vars.end(), [](const Var &v) { return v.record; }));
    for (const Var &v : vars) {
      // One record variable alone is stored unpadded.
      uint64_t stride = recordVars == 1 ? v.bytes : recordSize, last = 0;
      uint64_t end = 0;
      if (v.record && records > 0 &&
          (__builtin_mul_overflow(records - 1, stride, &last) ||
           __builtin_add_overflow(v.begin, last, &end) || __builtin_add_overflow(end, v.bytes, &end)))
        ok_ = false;
      if (!v.record && __builtin_add_overflow(v.begin, v.bytes, &end))
        ok_ = false;
      end_ = std::max(end_, end);
    }
  }

  std::string bytes_;
  uint64_t pos_ = 0;
  int version_ = 1;
  bool ok_ = true, needMore_ = false;
  uint64_t end_ = 0;
};

class ExodusReader {
public:
  ExodusReader(const std::string &path, int timeStep) : path_(path), timeStep_(timeStep) {}
  ~ExodusReader() {
    if (ncid_ >= 0)
      nc_close(ncid_);
  }
  ExodusReader(const ExodusReader &) = delete;
  ExodusReader &operator=(const ExodusReader &) = delete;

  /// The file's time steps: 1 for a mesh without results, which still renders as one step.
  int timeStepCount() {
    open();
    return int(std::clamp<uint64_t>(dimension("time_step", false), 1, uint64_t(INT32_MAX)));
  }

  UnstructuredGrid read() {
    open();
    UnstructuredGrid grid;
    const int dimensions = int(dimension("num_dim", true));
    if (dimensions < 1 || dimensions > 3)
      fail("dimension 'num_dim'", "expected 1, 2 or 3, got " + std::to_string(dimensions));
    const uint64_t nodes = dimension("num_nodes", false);
    readCoordinates(grid, dimensions, nodes);
    readTimeStep();

    grid.offsets.assign(1, 0);
    // Blocks in index order, found by their connect<b> variables: num_el_blk alone may claim any count.
    const uint64_t blockCount = dimension("num_el_blk", false);
    std::vector<uint64_t> blocks;
    // NFACED (polyhedral) blocks have facconn<b> instead.
    for (const std::string &name : variableNames_) {
      uint64_t b = 0;
      for (std::string_view prefix : {"connect", "facconn"})
        if (name.starts_with(prefix) && parseNumber(std::string_view(name).substr(prefix.size()), b) &&
            b >= 1 && b <= blockCount)
          blocks.push_back(b);
    }
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    std::vector<std::pair<uint64_t, uint64_t>> blockCells; // (block, elements) of the kept blocks
    for (uint64_t b : blocks)
      if (uint64_t cells = readBlock(grid, b, nodes))
        blockCells.emplace_back(b, cells);

    readNodalVariables(grid, nodes);
    readElementVariables(grid, blockCells);
    if (polyhedra_.polyhedronCount() > 0)
      decomposePolyhedra(grid, polyhedra_, path_);
    return grid;
  }

private:
  [[noreturn]] void fail(const std::string &position, const std::string &what) const {
    throw Error(path_, position, what);
  }
  void check(int status, const std::string &position, const std::string &what) const {
    if (status != NC_NOERR)
      fail(position, what + ": " + nc_strerror(status));
  }

  void open() {
    struct stat info {};
    errno = 0;
    if (::stat(path_.c_str(), &info) != 0 || !S_ISREG(info.st_mode))
      fail("", std::string("cannot open file: ") + (errno ? std::strerror(errno) : "not a regular file"));
    fileSize_ = uint64_t(info.st_size);
    char magic[4] = {};
    std::ifstream(path_, std::ios::binary).read(magic, 4);
    // netCDF-3 headers are checked here first: netCDF allocates what their counts claim before reading.
    if (std::string_view(magic, 3) == "CDF") {
      std::optional<uint64_t> end = ClassicHeader::dataEnd(path_, fileSize_);
      if (!end)
        fail("netCDF header", "not a readable netCDF file: malformed or truncated netCDF-3 header");
      if (*end > fileSize_)
        fail("netCDF header", "the header lays out " + std::to_string(*end) + " bytes but the file has " +
                                  std::to_string(fileSize_) + " (truncated?)");
    }
    check(nc_open(path_.c_str(), NC_NOWRITE, &ncid_), "netCDF header", "not a readable netCDF file");
    int format = 0;
    check(nc_inq_format(ncid_, &format), "netCDF header", "not a readable netCDF file");
    // netCDF-3 stores every value uncompressed; netCDF-4 (HDF5) may deflate, at most about 1032:1.
    const bool hdf5 = format == NC_FORMAT_NETCDF4 || format == NC_FORMAT_NETCDF4_CLASSIC;
    compressionLimit_ = hdf5 ? 1100 : 1;
    int count = 0;
    check(nc_inq_nvars(ncid_, &count), "netCDF header", "cannot list the variables");
    for (int id = 0; id < count; ++id) {
      char name[NC_MAX_NAME + 1] = {};
      check(nc_inq_varname(ncid_, id, name), "netCDF header", "cannot list the variables");
      variableNames_.emplace_back(name);
    }
  }

  /// Fails unless `count` variables (num_nod_var, num_elem_var) could each have their own netCDF variable.
  void checkVariableCount(const std::string &dimensionName, uint64_t count) const {
    if (count > variableNames_.size())
      fail("dimension '" + dimensionName + "'", std::to_string(count) +
                                                    " variables declared but the file has " +
                                                    std::to_string(variableNames_.size()) + " in all");
  }

  /// A dimension's length; 0 when absent and not `required`.
  uint64_t dimension(const std::string &name, bool required) const {
    int id = -1;
    if (nc_inq_dimid(ncid_, name.c_str(), &id) != NC_NOERR) {
      if (required)
        fail("dimension '" + name + "'", "missing: not an Exodus II file?");
      return 0;
    }
    size_t length = 0;
    check(nc_inq_dimlen(ncid_, id, &length), "dimension '" + name + "'", "cannot read");
    return length;
  }

  bool hasVariable(const std::string &name) const {
    int id = -1;
    return nc_inq_varid(ncid_, name.c_str(), &id) == NC_NOERR;
  }

  struct Variable {
    int id = -1;
    std::vector<size_t> shape;
    std::string position;
  };

  Variable variable(const std::string &name) const {
    Variable v;
    v.position = "variable '" + name + "'";
    check(nc_inq_varid(ncid_, name.c_str(), &v.id), v.position, "missing");
    int rank = 0;
    check(nc_inq_varndims(ncid_, v.id, &rank), v.position, "cannot read");
    if (rank < 0 || rank > NC_MAX_VAR_DIMS)
      fail(v.position, "impossible rank " + std::to_string(rank));
    std::vector<int> dims(size_t(rank) + 1);
    check(nc_inq_vardimid(ncid_, v.id, dims.data()), v.position, "cannot read");
    for (int d = 0; d < rank; ++d) {
      size_t length = 0;
      check(nc_inq_dimlen(ncid_, dims[size_t(d)], &length), v.position, "cannot read its dimensions");
      v.shape.push_back(length);
    }
    return v;
  }

  /// Fails unless `v` has exactly `expected` as its shape.
  void expectShape(const Variable &v, const std::vector<size_t> &expected) const {
    if (v.shape == expected)
      return;
    auto text = [](const std::vector<size_t> &shape) {
      std::string s = "(";
      for (size_t i = 0; i < shape.size(); ++i)
        s += (i ? ", " : "") + std::to_string(shape[i]);
      return s + ")";
    };
    fail(v.position, "has shape " + text(v.shape) + ", expected " + text(expected));
  }

  /// Fails unless `count` values more could be stored in this file, with all those read before (netCDF-4
  /// fills unwritten values in: a small file may declare any number), and fit in the memory limit: called
  /// before allocating for them.
  void checkRoom(const Variable &v, uint64_t count) {
    uint64_t total = 0, bytes = 0;
    if (__builtin_add_overflow(valuesClaimed_, count, &total) || total / compressionLimit_ > fileSize_)
      fail(v.position, std::to_string(count) + " values declared (" + std::to_string(total) +
                           " with the variables read before) but the file is only " +
                           std::to_string(fileSize_) + " bytes");
    if (__builtin_mul_overflow(total, uint64_t(sizeof(double)), &bytes))
      bytes = UINT64_MAX;
    if (bytes > fileSize_)
      checkMemoryLimit(path_, v.position, bytes, "its values with those read before");
    valuesClaimed_ = total;
  }

  /// The hyperslab of `v` at `start` with `count` values per dimension, converted to T.
  template <typename T>
  std::vector<T> readSlab(const Variable &v, const std::vector<size_t> &start,
                          const std::vector<size_t> &count) {
    uint64_t total = 1;
    for (size_t c : count)
      if (__builtin_mul_overflow(total, uint64_t(c), &total))
        fail(v.position, "value count overflows");
    checkRoom(v, total);
    std::vector<T> values(total);
    if (total == 0)
      return values;
    int status;
    if constexpr (std::is_same_v<T, double>)
      status = nc_get_vara_double(ncid_, v.id, start.data(), count.data(), values.data());
    else
      status = nc_get_vara_longlong(ncid_, v.id, start.data(), count.data(), values.data());
    check(status, v.position, "cannot read its values");
    return values;
  }

  template <typename T> std::vector<T> readWhole(const Variable &v) {
    return readSlab<T>(v, std::vector<size_t>(v.shape.size(), 0), v.shape);
  }

  std::string textAttribute(const Variable &v, const char *name) const {
    size_t length = 0;
    nc_type type = NC_NAT;
    if (nc_inq_att(ncid_, v.id, name, &type, &length) != NC_NOERR || type != NC_CHAR)
      fail(v.position, std::string("expected a text attribute '") + name + "'");
    if (length > fileSize_)
      fail(v.position, std::string("attribute '") + name + "' is longer than the file");
    std::string text(length, '\0');
    check(nc_get_att_text(ncid_, v.id, name, text.data()), v.position, "cannot read attribute");
    text.resize(std::min(text.size(), text.find('\0')));
    return text;
  }

  /// Rows of a char variable (n, len) as strings; `count` rows expected, missing names are numbered.
  std::vector<std::string> names(const std::string &name, uint64_t count, const std::string &prefix) {
    std::vector<std::string> result;
    if (hasVariable(name)) {
      Variable v = variable(name);
      nc_type type = NC_NAT;
      check(nc_inq_vartype(ncid_, v.id, &type), v.position, "cannot read");
      if (type != NC_CHAR || v.shape.size() != 2 || v.shape[0] != count)
        fail(v.position, "expected " + std::to_string(count) + " names");
      checkRoom(v, uint64_t(v.shape[0]) * v.shape[1]);
      std::string text(v.shape[0] * v.shape[1], '\0');
      if (!text.empty())
        check(nc_get_var_text(ncid_, v.id, text.data()), v.position, "cannot read its values");
      for (size_t i = 0; i < v.shape[0]; ++i) {
        std::string row = text.substr(i * v.shape[1], v.shape[1]);
        row.resize(std::min(row.size(), row.find('\0')));
        while (!row.empty() && row.back() == ' ')
          row.pop_back();
        result.push_back(row);
      }
    }
    result.resize(count);
    for (uint64_t i = 0; i < count; ++i)
      if (result[i].empty())
        result[i] = prefix + std::to_string(i + 1);
    return result;
  }

  void readCoordinates(UnstructuredGrid &grid, int dimensions, uint64_t nodes) {
    std::vector<std::vector<double>> axes;
    const char *axisNames[] = {"coordx", "coordy", "coordz"};
    const bool separate = hasVariable("coordx");
    if (separate) {
      for (int d = 0; d < dimensions; ++d) {
        Variable v = variable(axisNames[d]);
        expectShape(v, {nodes});
        axes.push_back(readWhole<double>(v));
      }
    } else if (hasVariable("coord")) {
      Variable v = variable("coord");
      expectShape(v, {size_t(dimensions), nodes});
      std::vector<double> all = readWhole<double>(v);
      for (int d = 0; d < dimensions; ++d)
        axes.emplace_back(all.begin() + ptrdiff_t(d * nodes), all.begin() + ptrdiff_t((d + 1) * nodes));
    } else if (nodes > 0) {
      fail("variable 'coordx'", "no coordinates: expected variables 'coordx', 'coordy', 'coordz' or 'coord'");
    }
    grid.points.resize(nodes);
    for (uint64_t i = 0; i < nodes; ++i) {
      float xyz[3] = {0.f, 0.f, 0.f};
      for (int d = 0; d < dimensions; ++d) {
        xyz[d] = float(axes[size_t(d)][i]);
        if (!std::isfinite(xyz[d]))
          fail(std::string("variable '") + (separate ? axisNames[d] : "coord") + "'",
               "coordinate of node " + std::to_string(i + 1) +
                   (std::isfinite(axes[size_t(d)][i]) ? " is out of float range" : " is not finite"));
      }
      grid.points[i] = {xyz[0], xyz[1], xyz[2]};
    }
  }

  void readTimeStep() {
    timeSteps_ = dimension("time_step", false);
    const bool none = timeSteps_ == 0 && timeStep_ == 0; // a mesh without results
    if (!none && (timeStep_ < 0 || uint64_t(timeStep_) >= timeSteps_))
      fail("dimension 'time_step'", "time step " + std::to_string(timeStep_) +
                                        " is out of range: the file has " + std::to_string(timeSteps_) +
                                        " time steps" +
                                        (timeSteps_ ? " (0.." + std::to_string(timeSteps_ - 1) + ")" : ""));
  }

  /// Appends block `b`'s cells to `grid`; returns how many, 0 if the block is skipped.
  uint64_t readBlock(UnstructuredGrid &grid, uint64_t b, uint64_t nodes) {
    const std::string index = std::to_string(b);
    const uint64_t elements = dimension("num_el_in_blk" + index, false);
    if (elements > 0 && !hasVariable("connect" + index) && hasVariable("facconn" + index))
      return readPolyhedronBlock(grid, index, elements);
    if (elements == 0 || !hasVariable("connect" + index))
      return 0; // an empty (null) block
    Variable v = variable("connect" + index);
    const uint64_t perElement = dimension("num_nod_per_el" + index, true);
    expectShape(v, {elements, perElement});
    const std::string typeName = textAttribute(v, "elem_type");
    uint8_t vtkType = 0;
    int corners = 0;
    if (!volumeType(baseTypeName(typeName), vtkType, corners)) {
      std::fprintf(stderr, "uvr: %s: skipped element block %s (%s, %llu elements): not a volume element\n",
                   path_.c_str(), index.c_str(), typeName.c_str(), static_cast<unsigned long long>(elements));
      return 0;
    }
    if (perElement < uint64_t(corners))
      fail(v.position, typeName + " elements need at least " + std::to_string(corners) + " nodes, have " +
                           std::to_string(perElement));
    if (perElement > uint64_t(corners))
      std::fprintf(stderr, "uvr: %s: element block %s (%s): higher-order elements read by their %d corners\n",
                   path_.c_str(), index.c_str(), typeName.c_str(), corners);

    const std::vector<long long> connect = readWhole<long long>(v);
    grid.connectivity.reserve(grid.connectivity.size() + elements * uint64_t(corners));
    for (uint64_t e = 0; e < elements; ++e) {
      for (int c = 0; c < corners; ++c) {
        const long long node = connect[e * perElement + uint64_t(c)]; // 1-based
        if (node < 1 || uint64_t(node) > nodes)
          fail(v.position, "element " + std::to_string(e + 1) + " refers to node " + std::to_string(node) +
                               ", outside [1, " + std::to_string(nodes) + "]");
        grid.connectivity.push_back(node - 1);
      }
      grid.offsets.push_back(int64_t(grid.connectivity.size()));
      grid.types.push_back(vtkType);
    }
    return elements;
  }

  /// Values at the chosen time step of a variable shaped (time_step, count).
  UninitVector<float> stepValues(const std::string &name, uint64_t count) {
    Variable v = variable(name);
    expectShape(v, {timeSteps_, count});
    return toFloat(readSlab<double>(v, {size_t(timeStep_), 0}, {1, count}));
  }

  static UninitVector<float> toFloat(const std::vector<double> &values) {
    return UninitVector<float>(values.begin(), values.end());
  }

  /// The faces of the face blocks (NSIDED: fbconn<f> holds each face's nodes, fbepecnt<f> their counts), in
  /// block order: NFACED elements number them from 1 across the blocks.
  void readFaceBlocks() {
    facesRead_ = true;
    const uint64_t faceBlocks = dimension("num_fa_blk", false);
    for (uint64_t f = 1; f <= faceBlocks; ++f) {
      const std::string index = std::to_string(f);
      if (!hasVariable("fbconn" + index))
        continue;
      const Variable counts = variable("fbepecnt" + index), nodes = variable("fbconn" + index);
      expectShape(counts, {dimension("num_fa_in_blk" + index, true)});
      expectShape(nodes, {dimension("num_nod_per_fa" + index, true)});
      uint64_t at = 0;
      const std::vector<long long> perFace = readWhole<long long>(counts);
      const std::vector<long long> ids = readWhole<long long>(nodes);
      for (long long n : perFace) {
        if (n < 3 || uint64_t(n) > ids.size() - at)
          fail(counts.position, "a face of " + std::to_string(n) +
                                    " nodes: fewer than 3, or more than fbconn" + index + " holds");
        for (uint64_t i = at; i < at + uint64_t(n); ++i)
          polyhedra_.facePoints.push_back(ids[i] - 1); // 1-based; checked with the cells
        polyhedra_.faceOffsets.push_back(int64_t(polyhedra_.facePoints.size()));
        at += uint64_t(n);
      }
      if (at != ids.size())
        fail(counts.position, "the faces use " + std::to_string(at) + " of the " +
                                  std::to_string(ids.size()) + " nodes of fbconn" + index);
    }
  }

  /// An NFACED block: ebepecnt<b> faces per element, facconn<b> their numbers (from 1). Its elements are
  /// polyhedra, decomposed once the fields are read.
  uint64_t readPolyhedronBlock(UnstructuredGrid &grid, const std::string &index, uint64_t elements) {
    if (!facesRead_)
      readFaceBlocks();
    const Variable counts = variable("ebepecnt" + index), faces = variable("facconn" + index);
    expectShape(counts, {elements});
    expectShape(faces, {dimension("num_fac_per_el" + index, true)});
    const std::vector<long long> perElement = readWhole<long long>(counts);
    const std::vector<long long> ids = readWhole<long long>(faces);
    uint64_t at = 0;
    for (long long n : perElement) {
      if (n < 1 || uint64_t(n) > ids.size() - at)
        fail(counts.position,
             "an element of " + std::to_string(n) + " faces: none, or more than facconn" + index + " holds");
      for (uint64_t i = at; i < at + uint64_t(n); ++i)
        polyhedra_.faceIds.push_back(ids[i] - 1); // checked by decomposePolyhedra
      polyhedra_.cellOffsets.push_back(int64_t(polyhedra_.faceIds.size()));
      at += uint64_t(n);
      grid.offsets.push_back(grid.offsets.back()); // the faces say it all
      grid.types.push_back(kVtkPolyhedron);
    }
    if (at != ids.size())
      fail(counts.position, "the elements use " + std::to_string(at) + " of the " +
                                std::to_string(ids.size()) + " faces of facconn" + index);
    return elements;
  }

  void readNodalVariables(UnstructuredGrid &grid, uint64_t nodes) {
    const uint64_t count = dimension("num_nod_var", false);
    if (count == 0 || timeSteps_ == 0)
      return;
    const bool combined = hasVariable("vals_nod_var"); // the layout before Exodus 4.x: one 3-D variable
    Variable all;
    if (combined) {
      all = variable("vals_nod_var");
      expectShape(all, {timeSteps_, count, nodes});
      uint64_t total = 0;
      if (__builtin_mul_overflow(count, uint64_t(nodes), &total))
        fail(all.position, "value count overflows");
      checkRoom(all, total);
    } else {
      checkVariableCount("num_nod_var", count);
    }
    const std::vector<std::string> varNames = names("name_nod_var", count, "node_variable_");
    for (uint64_t i = 0; i < count; ++i) {
      UninitVector<float> values =
          combined ? toFloat(readSlab<double>(all, {size_t(timeStep_), i, 0}, {1, 1, nodes}))
                   : stepValues("vals_nod_var" + std::to_string(i + 1), nodes);
      grid.fields.push_back({varNames[i], Centering::Point, std::move(values)});
    }
  }

  void readElementVariables(UnstructuredGrid &grid,
                            const std::vector<std::pair<uint64_t, uint64_t>> &blockCells) {
    const uint64_t count = dimension("num_elem_var", false);
    if (count == 0 || timeSteps_ == 0)
      return;
    checkVariableCount("num_elem_var", count);
    const std::vector<std::string> varNames = names("name_elem_var", count, "element_variable_");
    const uint64_t cells = grid.types.size();
    for (uint64_t i = 0; i < count; ++i) {
      ScalarField field{varNames[i], Centering::Cell, UninitVector<float>(cells, NAN)};
      uint64_t first = 0;
      for (auto [block, elements] : blockCells) {
        const std::string name = "vals_elem_var" + std::to_string(i + 1) + "eb" + std::to_string(block);
        if (hasVariable(name)) {
          const UninitVector<float> values = stepValues(name, elements);
          std::copy(values.begin(), values.end(), field.values.begin() + ptrdiff_t(first));
        }
        first += elements;
      }
      grid.fields.push_back(std::move(field));
    }
  }

  std::string path_;
  int timeStep_;
  int ncid_ = -1;
  uint64_t fileSize_ = 0;
  uint64_t compressionLimit_ = 1;
  uint64_t valuesClaimed_ = 0;
  uint64_t timeSteps_ = 0;
  std::vector<std::string> variableNames_;
  PolyhedronFaces polyhedra_; ///< of the NFACED blocks
  bool facesRead_ = false;
};

} // namespace

UnstructuredGrid readExodus(const std::string &path, int timeStep) {
  return ExodusReader(path, timeStep).read();
}

int exodusTimeStepCount(const std::string &path) { return ExodusReader(path, 0).timeStepCount(); }

} // namespace uvr

#else

namespace uvr {

namespace {
[[noreturn]] void refuseWithoutNetCdf(const std::string &path) {
  throw Error(path, "", "uvr was built without netCDF, so it cannot read Exodus II files");
}
} // namespace

UnstructuredGrid readExodus(const std::string &path, int) { refuseWithoutNetCdf(path); }
int exodusTimeStepCount(const std::string &path) { refuseWithoutNetCdf(path); }

} // namespace uvr

#endif
