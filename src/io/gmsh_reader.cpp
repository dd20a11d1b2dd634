// Gmsh .msh reader: formats 2.2 and 4.1, ascii and binary (either byte order).
//
// Volume elements become VTK cells; second- and higher-order ones keep their corner nodes, which Gmsh lists
// first. Gmsh's prism has its first triangle facing its second one, VTK's wedge faces away from it, so
// prisms are mirrored (1 <-> 2, 4 <-> 5); tets, hexahedra and pyramids number their corners as VTK does.
// Lower-dimensional elements become VTK cells of their dimension without points: buildMesh counts and drops
// them. $NodeData and $ElementData become point and cell fields, at the time step asked for.
#include "core/progress.h"
#include "io/binary.h"
#include "io/file_buffer.h"
#include "io/mesh_io.h"
#include "io/text_scan.h"
#include <uvr/error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string_view>

namespace uvr {

namespace {

/// What uvr needs of a Gmsh element type.
struct ElementType {
  int nodes = 0;
  int dimension = 0;
  uint8_t vtkType = 0; ///< the linear VTK type of the volume elements; a VTK type of that dimension otherwise
  int corners = 0;     ///< nodes kept
};

ElementType elementType(int gmshType) {
  constexpr uint8_t kVertex = 1, kLine = 3, kTriangle = 5, kQuad = 9;
  constexpr uint8_t kTet = 10, kHex = 12, kWedge = 13, kPyramid = 14;
  switch (gmshType) {
  case 1:
    return {2, 1, kLine, 0};
  case 2:
    return {3, 2, kTriangle, 0};
  case 3:
    return {4, 2, kQuad, 0};
  case 4:
    return {4, 3, kTet, 4};
  case 5:
    return {8, 3, kHex, 8};
  case 6:
    return {6, 3, kWedge, 6};
  case 7:
    return {5, 3, kPyramid, 5};
  case 8:
    return {3, 1, kLine, 0};
  case 9:
    return {6, 2, kTriangle, 0};
  case 10:
    return {9, 2, kQuad, 0};
  case 11:
    return {10, 3, kTet, 4};
  case 12:
    return {27, 3, kHex, 8};
  case 13:
    return {18, 3, kWedge, 6};
  case 14:
    return {14, 3, kPyramid, 5};
  case 15:
    return {1, 0, kVertex, 0};
  case 16:
    return {8, 2, kQuad, 0};
  case 17:
    return {20, 3, kHex, 8};
  case 18:
    return {15, 3, kWedge, 6};
  case 19:
    return {13, 3, kPyramid, 5};
  case 20:
    return {9, 2, kTriangle, 0};
  case 21:
    return {10, 2, kTriangle, 0};
  case 22:
    return {12, 2, kTriangle, 0};
  case 23:
    return {15, 2, kTriangle, 0};
  case 24:
    return {15, 2, kTriangle, 0};
  case 25:
    return {21, 2, kTriangle, 0};
  case 26:
    return {4, 1, kLine, 0};
  case 27:
    return {5, 1, kLine, 0};
  case 28:
    return {6, 1, kLine, 0};
  case 29:
    return {20, 3, kTet, 4};
  case 30:
    return {35, 3, kTet, 4};
  case 31:
    return {56, 3, kTet, 4};
  case 92:
    return {64, 3, kHex, 8};
  case 93:
    return {125, 3, kHex, 8};
  default:
    return {};
  }
}

/// Maps sparse tags (node or element numbers) to 0-based indices.
class TagMap {
public:
  /// `maxTag` bounds the tags when known (0 otherwise).
  void build(const std::vector<uint64_t> &tags) {
    uint64_t largest = 0;
    for (uint64_t tag : tags)
      largest = std::max(largest, tag);
    dense_ = largest <= 4 * tags.size() + 1024;
    if (dense_) {
      index_.assign(largest + 1, -1);
      for (size_t i = 0; i < tags.size(); ++i) {
        if (index_[tags[i]] >= 0)
          duplicate_ = tags[i];
        index_[tags[i]] = int64_t(i);
      }
    } else {
      sorted_.resize(tags.size());
      for (size_t i = 0; i < tags.size(); ++i)
        sorted_[i] = {tags[i], int64_t(i)};
      std::sort(sorted_.begin(), sorted_.end());
      for (size_t i = 1; i < sorted_.size(); ++i)
        if (sorted_[i].first == sorted_[i - 1].first)
          duplicate_ = sorted_[i].first;
    }
  }
  /// The index of `tag`, or -1.
  int64_t find(uint64_t tag) const {
    if (dense_)
      return tag < index_.size() ? index_[tag] : -1;
    auto it = std::lower_bound(sorted_.begin(), sorted_.end(), std::pair<uint64_t, int64_t>{tag, INT64_MIN});
    return it != sorted_.end() && it->first == tag ? it->second : -1;
  }
  /// A tag listed twice, or 0.
  uint64_t duplicate() const { return duplicate_; }

private:
  bool dense_ = true;
  std::vector<int64_t> index_;
  std::vector<std::pair<uint64_t, int64_t>> sorted_;
  uint64_t duplicate_ = 0;
};

/// One $NodeData or $ElementData section, its values kept by tag until the mesh is known.
struct DataBlock {
  std::string name;
  Centering centering;
  int64_t timeStep = 0;
  uint64_t position = 0;
  std::vector<std::pair<uint64_t, float>> values; ///< tag and value (the magnitude of several components)
};

class GmshReader {
public:
  GmshReader(const std::string &path, const LoadOptions &options)
      : path_(path), options_(options), file_(readFile(path)), begin_(file_.chars()), p_(begin_),
        end_(begin_ + file_.size), progress_("reading " + path, file_.size) {}

  UnstructuredGrid read(int *timeStepCount) {
    bool sawFormat = false, sawNodes = false, sawElements = false;
    while (true) {
      skipSpace();
      if (p_ == end_)
        break;
      const uint64_t at = here();
      if (*p_ != '$')
        fail(at, "expected a section such as $Nodes, got '" + std::string(peekToken()) + "'");
      const std::string name(restOfLine().substr(1));
      if (!sawFormat && name != "MeshFormat")
        fail(at, "expected $MeshFormat first, got $" + name);
      if (name == "MeshFormat") {
        readFormat();
        sawFormat = true;
      } else if (name == "Nodes") {
        version4_ ? readNodes4() : readNodes2();
        sawNodes = true;
      } else if (name == "Elements") {
        if (!sawNodes)
          fail(at, "$Elements before $Nodes");
        version4_ ? readElements4() : readElements2();
        sawElements = true;
      } else if (name == "NodeData" || name == "ElementData") {
        readData(name == "NodeData" ? Centering::Point : Centering::Cell, at);
        continue; // readData consumed its end marker
      } else {
        skipSection(name, at);
        continue;
      }
      expectEnd(name);
      progress_.set(here());
    }
    if (!sawNodes || !sawElements)
      fail(here(), std::string("the file ends without a $") + (sawNodes ? "Elements" : "Nodes") + " section");
    finishCells();
    finishFields(timeStepCount);
    progress_.finish();
    if (higherOrder_ > 0)
      std::fprintf(stderr, "uvr: %s: %llu second- or higher-order cells kept by their corner nodes\n",
                   path_.c_str(), static_cast<unsigned long long>(higherOrder_));
    return std::move(grid_);
  }

private:
  [[noreturn]] void fail(uint64_t at, const std::string &what) const {
    throw Error(path_, "byte " + std::to_string(at), what);
  }
  uint64_t here() const { return uint64_t(p_ - begin_); }
  uint64_t remaining() const { return uint64_t(end_ - p_); }

  void skipSpace() { p_ = uvr::skipSpace(p_, end_); }
  std::string_view peekToken() const {
    const char *e = p_;
    while (e != end_ && !isSpace(*e) && e - p_ < 40)
      ++e;
    return {p_, size_t(e - p_)};
  }
  /// The rest of the current line without its line break; moves past it.
  std::string_view restOfLine() {
    const char *start = p_;
    while (p_ != end_ && *p_ != '\n')
      ++p_;
    std::string_view line(start, size_t(p_ - start));
    if (p_ != end_)
      ++p_;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
      line.remove_suffix(1);
    return line;
  }

  /// A number written as text.
  template <typename T> T text(const char *what) {
    skipSpace();
    if (p_ == end_)
      fail(here(), std::string("the file ends before ") + what);
    const char *stop = tokenEnd(p_, end_);
    T value{};
    if (!parseNumber(p_, stop, value))
      fail(here(), std::string("expected ") + what + ", got '" + std::string(peekToken()) + "'");
    p_ = stop;
    return value;
  }

  /// A number stored in binary, in the file's byte order.
  template <typename T> T binary(const char *what) {
    if (remaining() < sizeof(T))
      fail(here(), std::string("the file ends before ") + what);
    const T value = loadValue<T>(p_, swap_);
    p_ += sizeof(T);
    return value;
  }

  /// An integer that version 4.1 stores as size_t and 2.2 as text: counts and tags of $Nodes and $Elements.
  uint64_t count(const char *what) {
    return binary_ && version4_ ? binary<uint64_t>(what) : text<uint64_t>(what);
  }
  int64_t integer(const char *what) { return binary_ ? binary<int32_t>(what) : text<int64_t>(what); }
  double real(const char *what) { return binary_ ? binary<double>(what) : text<double>(what); }

  /// Fails unless `n` items of at least `bytes` bytes each fit in the rest of the file: called before
  /// allocating for them.
  void expectRoom(uint64_t n, uint64_t bytes, uint64_t at, const std::string &what) const {
    if (n > remaining() / bytes)
      fail(at, std::to_string(n) + " " + what + " declared, but only " + std::to_string(remaining()) +
                   " bytes follow");
  }

  void expectEnd(const std::string &name) {
    skipSpace();
    const uint64_t at = here();
    const std::string_view line = restOfLine();
    if (line != "$End" + name)
      fail(at, "expected $End" + name + ", got '" + std::string(line.substr(0, 40)) + "'");
  }

  void skipSection(const std::string &name, uint64_t at) {
    const std::string marker = "$End" + name;
    const std::string_view rest(p_, remaining());
    for (size_t found = rest.find(marker); found != std::string_view::npos;
         found = rest.find(marker, found + 1))
      if (found == 0 || rest[found - 1] == '\n') {
        p_ += found;
        restOfLine();
        return;
      }
    fail(at, "section $" + name + " has no " + marker);
  }

  void readFormat() {
    const double version = text<double>("the format version");
    const int fileType = text<int>("the file type (0 ascii, 1 binary)");
    const int dataSize = text<int>("the data size");
    if (version >= 4.1 && version < 4.2)
      version4_ = true;
    else if (!(version >= 2.0 && version < 3.0))
      fail(0, "Gmsh format " + std::to_string(version).substr(0, 3) + " is not supported (2.2 and 4.1 are)");
    if (fileType != 0 && fileType != 1)
      fail(0, "unknown file type " + std::to_string(fileType));
    if (dataSize != 8)
      fail(0, "data size " + std::to_string(dataSize) + " is not supported (8 is)");
    binary_ = fileType == 1;
    restOfLine();
    if (binary_) {
      const uint64_t at = here();
      const int32_t one = binary<int32_t>("the byte-order mark");
      if (one != 1) {
        if (byteSwapped(one) != 1)
          fail(at, "the byte-order mark is " + std::to_string(one) + ", expected 1");
        swap_ = true;
      }
    }
  }

  void addPoint(double x, double y, double z, uint64_t at) {
    const Vec3f p{float(x), float(y), float(z)};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      fail(at, "node " + std::to_string(grid_.points.size()) + " is not finite in single precision");
    grid_.points.push_back(p);
  }

  void readNodes2() {
    const uint64_t at = here();
    const uint64_t n = text<uint64_t>("the node count");
    restOfLine();
    expectRoom(n, binary_ ? 28 : 8, at, "nodes");
    nodeTags_.reserve(n);
    grid_.points.reserve(n);
    for (uint64_t i = 0; i < n; ++i) {
      const uint64_t nodeAt = here();
      const int64_t tag = integer("a node number");
      if (tag <= 0)
        fail(nodeAt, "node number " + std::to_string(tag) + " is not positive");
      nodeTags_.push_back(uint64_t(tag));
      const double x = real("a node's x"), y = real("a node's y"), z = real("a node's z");
      addPoint(x, y, z, nodeAt);
    }
    mapNodes(at);
  }

  void readNodes4() {
    const uint64_t at = here();
    const uint64_t blocks = count("the node block count"), n = count("the node count");
    count("the smallest node tag");
    count("the largest node tag");
    expectRoom(n, binary_ ? 32 : 8, at, "nodes");
    expectRoom(blocks, binary_ ? 20 : 8, at, "node blocks");
    nodeTags_.reserve(n);
    grid_.points.reserve(n);
    for (uint64_t b = 0; b < blocks; ++b) {
      const uint64_t blockAt = here();
      const int64_t dimension = integer("a node block's entity dimension");
      integer("a node block's entity tag");
      const int64_t parametric = integer("a node block's parametric flag");
      const uint64_t inBlock = count("a node block's node count");
      if (dimension < 0 || dimension > 3 || (parametric != 0 && parametric != 1))
        fail(blockAt, "malformed node block header");
      if (inBlock > n - nodeTags_.size())
        fail(blockAt, "node blocks hold more than the " + std::to_string(n) + " nodes declared");
      const uint64_t coordinates = 3 + uint64_t(parametric ? dimension : 0);
      expectRoom(inBlock, binary_ ? 8 + 8 * coordinates : 2 + 2 * coordinates, blockAt, "nodes");
      for (uint64_t i = 0; i < inBlock; ++i) {
        const uint64_t tagAt = here();
        const uint64_t tag = count("a node tag");
        if (tag == 0)
          fail(tagAt, "node tag 0 (tags start at 1)");
        nodeTags_.push_back(tag);
      }
      for (uint64_t i = 0; i < inBlock; ++i) {
        const uint64_t nodeAt = here();
        double xyz[3];
        for (uint64_t c = 0; c < coordinates; ++c) {
          const double v = real("a node coordinate");
          if (c < 3)
            xyz[c] = v;
        }
        addPoint(xyz[0], xyz[1], xyz[2], nodeAt);
      }
    }
    if (nodeTags_.size() != n)
      fail(at, "node blocks hold " + std::to_string(nodeTags_.size()) + " nodes, " + std::to_string(n) +
                   " declared");
    mapNodes(at);
  }

  void mapNodes(uint64_t at) {
    nodes_.build(nodeTags_);
    if (nodes_.duplicate())
      fail(at, "node tag " + std::to_string(nodes_.duplicate()) + " is listed twice");
  }

  /// Appends one element given its node tags; `at` locates it for errors.
  void addElement(uint64_t tag, const ElementType &type, const uint64_t *nodeTags, uint64_t at) {
    elementTags_.push_back(tag);
    grid_.types.push_back(type.vtkType);
    if (type.dimension == 3) {
      int64_t corners[8];
      for (int i = 0; i < type.corners; ++i) {
        corners[i] = nodes_.find(nodeTags[i]);
        if (corners[i] < 0)
          fail(at, "element " + std::to_string(tag) + " names node " + std::to_string(nodeTags[i]) +
                       ", which $Nodes does not list");
      }
      if (type.vtkType == 13) { // Gmsh's prism faces its top, VTK's wedge faces away
        std::swap(corners[1], corners[2]);
        std::swap(corners[4], corners[5]);
      }
      grid_.connectivity.insert(grid_.connectivity.end(), corners, corners + type.corners);
      higherOrder_ += type.nodes > type.corners;
    }
    grid_.offsets.push_back(int64_t(grid_.connectivity.size()));
  }

  ElementType knownType(int64_t gmshType, uint64_t at) const {
    const ElementType type = gmshType > 0 && gmshType < 1000 ? elementType(int(gmshType)) : ElementType{};
    if (type.nodes == 0)
      fail(at, "unsupported Gmsh element type " + std::to_string(gmshType));
    return type;
  }

  void readElements2() {
    const uint64_t at = here();
    const uint64_t n = text<uint64_t>("the element count");
    restOfLine();
    expectRoom(n, binary_ ? 12 : 8, at, "elements");
    grid_.offsets.assign(1, 0);
    grid_.types.reserve(n);
    elementTags_.reserve(n);
    uint64_t nodeTags[125];
    if (!binary_) {
      for (uint64_t e = 0; e < n; ++e) {
        const uint64_t elementAt = here();
        const int64_t tag = text<int64_t>("an element number");
        const int64_t gmshType = text<int64_t>("an element type");
        const ElementType type = knownType(gmshType, elementAt);
        const int64_t tags = text<int64_t>("an element's tag count");
        if (tags < 0 || uint64_t(tags) > remaining() / 2)
          fail(elementAt, "element " + std::to_string(tag) + " has " + std::to_string(tags) + " tags");
        for (int64_t t = 0; t < tags; ++t)
          text<int64_t>("an element tag");
        for (int i = 0; i < type.nodes; ++i)
          nodeTags[i] = text<uint64_t>("an element's node");
        addElement(uint64_t(tag), type, nodeTags, elementAt);
        if (e % 65536 == 0)
          progress_.set(here());
      }
      return;
    }
    for (uint64_t e = 0; e < n;) {
      const uint64_t blockAt = here();
      const int64_t gmshType = binary<int32_t>("an element type");
      const ElementType type = knownType(gmshType, blockAt);
      const int64_t following = binary<int32_t>("an element block's count");
      const int64_t tags = binary<int32_t>("an element block's tag count");
      if (following <= 0 || uint64_t(following) > n - e || tags < 0)
        fail(blockAt, "malformed element block header");
      expectRoom(uint64_t(following), 4 * (1 + uint64_t(tags) + uint64_t(type.nodes)), blockAt, "elements");
      for (int64_t i = 0; i < following; ++i, ++e) {
        const uint64_t elementAt = here();
        const int64_t tag = binary<int32_t>("an element number");
        p_ += 4 * tags;
        for (int k = 0; k < type.nodes; ++k)
          nodeTags[k] = uint64_t(uint32_t(binary<int32_t>("an element's node")));
        addElement(uint64_t(tag), type, nodeTags, elementAt);
      }
    }
  }

  void readElements4() {
    const uint64_t at = here();
    const uint64_t blocks = count("the element block count"), n = count("the element count");
    count("the smallest element tag");
    count("the largest element tag");
    expectRoom(n, binary_ ? 16 : 4, at, "elements");
    expectRoom(blocks, binary_ ? 20 : 8, at, "element blocks");
    grid_.offsets.assign(1, 0);
    grid_.types.reserve(n);
    elementTags_.reserve(n);
    uint64_t nodeTags[125];
    for (uint64_t b = 0; b < blocks; ++b) {
      const uint64_t blockAt = here();
      integer("an element block's entity dimension");
      integer("an element block's entity tag");
      const ElementType type = knownType(integer("an element type"), blockAt);
      const uint64_t inBlock = count("an element block's element count");
      if (inBlock > n - elementTags_.size())
        fail(blockAt, "element blocks hold more than the " + std::to_string(n) + " elements declared");
      expectRoom(inBlock, (binary_ ? 8 : 2) * (1 + uint64_t(type.nodes)), blockAt, "elements");
      for (uint64_t i = 0; i < inBlock; ++i) {
        const uint64_t elementAt = here();
        const uint64_t tag = count("an element tag");
        for (int k = 0; k < type.nodes; ++k)
          nodeTags[k] = count("an element's node");
        addElement(tag, type, nodeTags, elementAt);
        if (i % 65536 == 0)
          progress_.set(here());
      }
    }
    if (elementTags_.size() != n)
      fail(at, "element blocks hold " + std::to_string(elementTags_.size()) + " elements, " +
                   std::to_string(n) + " declared");
  }

  /// A string tag: quoted, or (as some writers do) bare up to the line's end.
  std::string quoted() {
    skipSpace();
    const std::string_view line = restOfLine();
    if (line.size() >= 2 && line.front() == '"' && line.back() == '"')
      return std::string(line.substr(1, line.size() - 2));
    return std::string(line);
  }

  void readData(Centering centering, uint64_t at) {
    const std::string section = centering == Centering::Point ? "NodeData" : "ElementData";
    DataBlock block;
    block.centering = centering;
    block.position = at;
    const int64_t strings = text<int64_t>("the string tag count");
    if (strings < 0 || uint64_t(strings) > remaining())
      fail(at, "malformed $" + section + " header");
    for (int64_t i = 0; i < strings; ++i) {
      std::string tag = quoted();
      if (i == 0)
        block.name = std::move(tag);
    }
    const int64_t reals = text<int64_t>("the real tag count");
    if (reals < 0 || uint64_t(reals) > remaining())
      fail(at, "malformed $" + section + " header");
    for (int64_t i = 0; i < reals; ++i)
      text<double>("a real tag");
    const int64_t integers = text<int64_t>("the integer tag count");
    if (integers < 3 || uint64_t(integers) > remaining())
      fail(at, "$" + section + " needs at least 3 integer tags (time step, components, count)");
    int64_t values[3];
    for (int64_t i = 0; i < integers; ++i) {
      const int64_t v = text<int64_t>("an integer tag");
      if (i < 3)
        values[i] = v;
    }
    block.timeStep = values[0];
    const int64_t components = values[1], n = values[2];
    if (components < 1 || components > 9 || n < 0)
      fail(at, "$" + section + " '" + block.name + "' has " + std::to_string(components) +
                   " components and " + std::to_string(n) + " entries");
    if (block.name.empty())
      block.name = section;
    restOfLine();
    expectRoom(uint64_t(n), binary_ ? 4 + 8 * uint64_t(components) : 2 * (1 + uint64_t(components)), here(),
               "entries of $" + section + " '" + block.name + "'");
    block.values.reserve(uint64_t(n));
    for (int64_t i = 0; i < n; ++i) {
      const uint64_t entryAt = here();
      const int64_t tag = integer("an entity tag");
      if (tag <= 0)
        fail(entryAt, "tag " + std::to_string(tag) + " in $" + section + " '" + block.name + "'");
      double first = 0.0, sum = 0.0;
      for (int64_t c = 0; c < components; ++c) {
        const double v = real("a value");
        first = c == 0 ? v : first;
        sum += v * v;
      }
      // Several components become their magnitude, as in the VTK readers.
      block.values.push_back({uint64_t(tag), float(components == 1 ? first : std::sqrt(sum))});
    }
    expectEnd(section);
    blocks_.push_back(std::move(block));
  }

  void finishCells() {
    elements_.build(elementTags_);
    if (elements_.duplicate())
      fail(0, "element tag " + std::to_string(elements_.duplicate()) + " is listed twice");
  }

  /// Each field (by name and centering) at the asked time step: the n-th distinct step index of its blocks;
  /// a field with one step only is the same at every step. Blocks of one step (partitions) are merged.
  void finishFields(int *timeStepCount) {
    std::map<std::pair<std::string, Centering>, std::vector<const DataBlock *>> groups;
    std::vector<std::pair<std::string, Centering>> order;
    for (const DataBlock &block : blocks_) {
      auto key = std::make_pair(block.name, block.centering);
      if (!groups.count(key))
        order.push_back(key);
      groups[key].push_back(&block);
    }
    auto stepIndices = [](const std::vector<const DataBlock *> &blocks) {
      std::vector<int64_t> indices;
      for (const DataBlock *block : blocks)
        indices.push_back(block->timeStep);
      std::sort(indices.begin(), indices.end());
      indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
      return indices;
    };
    int steps = 1;
    for (const auto &group : groups)
      steps = std::max(steps, int(stepIndices(group.second).size()));
    if (timeStepCount)
      *timeStepCount = steps;
    if (options_.timeStep < 0 || options_.timeStep >= steps)
      throw Error(path_, "",
                  "time step " + std::to_string(options_.timeStep) + " asked, the file has " +
                      std::to_string(steps) + " (0 to " + std::to_string(steps - 1) + ")");

    for (const auto &key : order) {
      const std::vector<const DataBlock *> &blocks = groups[key];
      const std::vector<int64_t> indices = stepIndices(blocks);
      if (options_.timeStep >= int(indices.size()) && indices.size() > 1)
        throw Error(path_, "",
                    "field '" + key.first + "' has " + std::to_string(indices.size()) + " time steps, step " +
                        std::to_string(options_.timeStep) + " asked");
      const int64_t step = indices.size() == 1 ? indices[0] : indices[size_t(options_.timeStep)];

      const bool point = key.second == Centering::Point;
      const TagMap &map = point ? nodes_ : elements_;
      const uint64_t size = point ? grid_.points.size() : grid_.types.size();
      ScalarField field{key.first, key.second, UninitVector<float>(size, 0.f)};
      std::vector<uint8_t> given(size, 0);
      for (const DataBlock *block : blocks) {
        if (block->timeStep != step)
          continue;
        for (const auto &[tag, value] : block->values) {
          const int64_t index = map.find(tag);
          if (index < 0)
            fail(block->position, "$" + std::string(point ? "NodeData" : "ElementData") + " '" + key.first +
                                      "' names " + (point ? "node " : "element ") + std::to_string(tag) +
                                      ", which the mesh does not list");
          field.values[size_t(index)] = value;
          given[size_t(index)] = 1;
        }
      }
      // Every point, and every volume cell (the only cells kept), needs a value.
      for (uint64_t i = 0; i < size; ++i)
        if (!given[i] && (point || vertexCount(grid_.types[i]) > 0))
          fail(blocks.front()->position, "field '" + key.first + "' has no value at " +
                                             (point ? "node " : "element ") +
                                             std::to_string(point ? nodeTags_[i] : elementTags_[i]) +
                                             " in time step " + std::to_string(step));
      grid_.fields.push_back(std::move(field));
    }
  }

  std::string path_;
  LoadOptions options_;
  FileBuffer file_;
  const char *begin_, *p_, *end_;
  Progress progress_;
  bool version4_ = false, binary_ = false, swap_ = false;
  std::vector<uint64_t> nodeTags_, elementTags_;
  TagMap nodes_, elements_;
  std::vector<DataBlock> blocks_;
  uint64_t higherOrder_ = 0;
  UnstructuredGrid grid_;
};

} // namespace

UnstructuredGrid readGmsh(const std::string &path, const LoadOptions &options, int *timeStepCount) {
  return GmshReader(path, options).read(timeStepCount);
}

} // namespace uvr
