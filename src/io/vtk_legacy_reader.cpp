// Legacy VTK (.vtk) unstructured grid reader: ASCII and big-endian BINARY files.
//
// Keyword lines are read whole (in BINARY files the data starts right after the line's newline); values are
// read as whitespace-separated text or as packed big-endian binary.
#include "io/file_buffer.h"
#include "io/mesh_io.h"
#include "io/scalar_type.h"
#include "mesh/polyhedra.h"
#include <uvr/error.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <span>
#include <string_view>

namespace uvr {

namespace {

std::string join(const std::vector<std::string_view> &tokens) {
  std::string text;
  for (std::string_view token : tokens) {
    if (!text.empty())
      text += ' ';
    text += token;
  }
  return text.size() > 80 ? text.substr(0, 80) + "..." : text;
}

/// VTK 5.1 writers encode special characters of names as %XX.
std::string decodeName(std::string_view name) {
  std::string result;
  for (size_t i = 0; i < name.size(); ++i) {
    unsigned value = 0;
    if (name[i] == '%' && i + 2 < name.size() &&
        std::from_chars(name.data() + i + 1, name.data() + i + 3, value, 16).ptr == name.data() + i + 3) {
      result += char(value);
      i += 2;
    } else {
      result += name[i];
    }
  }
  return result;
}

/// A data type of the format: packed numbers of a ScalarType, bits (packed 8 to a byte, the first in the
/// highest bit) or strings.
struct DataType {
  enum class Kind : uint8_t { Number, Bit, String };
  Kind kind = Kind::Number;
  /// The packed numbers' type; UInt8 for bits (whose text is integers).
  ScalarType number = ScalarType::UInt8;

  bool isString() const { return kind == Kind::String; }
  /// Whether its values are integers: all but the floating types (bits and strings too).
  bool isInteger() const { return kind != Kind::Number || uvr::isInteger(number); }
};

constexpr DataType numeric(ScalarType type) { return {DataType::Kind::Number, type}; }

std::optional<DataType> parseDataType(std::string_view name) {
  static constexpr std::pair<std::string_view, DataType> names[] = {
      {"BIT", {DataType::Kind::Bit, ScalarType::UInt8}},
      {"CHAR", numeric(ScalarType::Int8)},
      {"SIGNED_CHAR", numeric(ScalarType::Int8)},
      {"UNSIGNED_CHAR", numeric(ScalarType::UInt8)},
      {"SHORT", numeric(ScalarType::Int16)},
      {"UNSIGNED_SHORT", numeric(ScalarType::UInt16)},
      {"INT", numeric(ScalarType::Int32)},
      {"UNSIGNED_INT", numeric(ScalarType::UInt32)},
      {"LONG", numeric(ScalarType::Int64)}, // VTK writes sizeof(long): 8 bytes on the LP64 systems we run on
      {"UNSIGNED_LONG", numeric(ScalarType::UInt64)},
      {"VTKIDTYPE", numeric(ScalarType::Int32)}, // written as int, as VTK's reader expects
      {"VTKTYPEINT8", numeric(ScalarType::Int8)},
      {"VTKTYPEUINT8", numeric(ScalarType::UInt8)},
      {"VTKTYPEINT16", numeric(ScalarType::Int16)},
      {"VTKTYPEUINT16", numeric(ScalarType::UInt16)},
      {"VTKTYPEINT32", numeric(ScalarType::Int32)},
      {"VTKTYPEUINT32", numeric(ScalarType::UInt32)},
      {"VTKTYPEINT64", numeric(ScalarType::Int64)},
      {"VTKTYPEUINT64", numeric(ScalarType::UInt64)},
      {"FLOAT", numeric(ScalarType::Float32)},
      {"VTKTYPEFLOAT32", numeric(ScalarType::Float32)},
      {"DOUBLE", numeric(ScalarType::Float64)},
      {"VTKTYPEFLOAT64", numeric(ScalarType::Float64)},
      {"STRING", {DataType::Kind::String, ScalarType::UInt8}},
      {"UTF8_STRING", {DataType::Kind::String, ScalarType::UInt8}},
  };
  std::string key = toUpper(name);
  for (auto [text, type] : names)
    if (text == key)
      return type;
  return std::nullopt;
}

/// Bytes that `count` binary values of `type` take (strings: at least that many).
uint64_t binaryBytes(DataType type, uint64_t count) {
  if (type.kind == DataType::Kind::Bit)
    return count / 8 + (count % 8 != 0);
  if (type.isString())
    return count;
  uint64_t bytes = 0;
  return __builtin_mul_overflow(count, scalarSize(type.number), &bytes) ? UINT64_MAX : bytes;
}

using Line = std::vector<std::string_view>;

class LegacyReader {
public:
  explicit LegacyReader(const std::string &path)
      : path_(path), file_(readFile(path)), begin_(file_.chars()), pos_(begin_), end_(begin_ + file_.size) {}

  UnstructuredGrid read() {
    std::string_view version = rawLine();
    if (toUpper(version.substr(0, 14)) != "# VTK DATAFILE")
      failLine("expected '# vtk DataFile Version x.x', got '" + std::string(version.substr(0, 40)) + "'");
    rawLine(); // the title
    Line format = readLine();
    if (format.size() != 1 || (toUpper(format[0]) != "ASCII" && toUpper(format[0]) != "BINARY"))
      failLine("expected 'ASCII' or 'BINARY', got '" + join(format) + "'");
    binary_ = toUpper(format[0]) == "BINARY";
    Line dataset = readLine();
    if (dataset.size() != 2 || toUpper(dataset[0]) != "DATASET")
      failLine("expected 'DATASET UNSTRUCTURED_GRID', got '" + join(dataset) + "'");
    if (toUpper(dataset[1]) != "UNSTRUCTURED_GRID")
      failLine("unsupported dataset type '" + std::string(dataset[1]) + "' (expected UNSTRUCTURED_GRID)");

    grid_.offsets.assign(1, 0);

    for (Line line = readLine(); !line.empty(); line = readLine())
      readSection(line);
    return finish();
  }

private:
  // Errors. Positions are lines until the first binary data is read, then bytes (binary data holds
  // newline bytes that are not lines).
  std::string where(const char *at, uint64_t line) const {
    return sawBinary_ ? "byte " + std::to_string(at - begin_) : "line " + std::to_string(line);
  }
  [[noreturn]] void failLine(const std::string &what) const {
    throw Error(path_, where(lineStart_, lineNumber_), what);
  }
  [[noreturn]] void failToken(const std::string &what) const {
    throw Error(path_, where(tokenStart_, tokenLine_), what);
  }
  [[noreturn]] void failAt(const std::string &position, const std::string &what) const {
    throw Error(path_, position, what);
  }

  // Lexing.

  /// The next line without its newline; the cursor moves past it.
  std::string_view rawLine() {
    lineStart_ = pos_;
    lineNumber_ = line_;
    auto newline = static_cast<const char *>(std::memchr(pos_, '\n', size_t(end_ - pos_)));
    std::string_view text(pos_, size_t((newline ? newline : end_) - pos_));
    pos_ = newline ? newline + 1 : end_;
    line_ += newline != nullptr;
    if (!text.empty() && text.back() == '\r')
      text.remove_suffix(1);
    return text;
  }

  /// The tokens of the next non-blank line; none at the end of the file.
  Line readLine() {
    while (pos_ < end_) {
      std::string_view text = rawLine();
      Line tokens = splitTokens(text);
      if (!tokens.empty())
        return tokens;
    }
    return {};
  }

  /// Whether the next non-blank line starts with `keyword` (any case); reads nothing.
  bool nextLineStartsWith(std::string_view keyword) const {
    const char *p = skipSpace(pos_, end_);
    if (uint64_t(end_ - p) < keyword.size() || toUpper(std::string_view(p, keyword.size())) != keyword)
      return false;
    p += keyword.size();
    return p == end_ || isSpace(*p);
  }

  /// The next whitespace-separated value of ASCII data; empty at the end of the file.
  std::string_view valueToken() {
    tokenStart_ = skipSpace(pos_, end_);
    line_ += uint64_t(std::count(pos_, tokenStart_, '\n'));
    tokenLine_ = line_;
    pos_ = tokenEnd(tokenStart_, end_);
    return {tokenStart_, size_t(pos_ - tokenStart_)};
  }

  uint64_t count(std::string_view token, const Line &line, const char *expected) const {
    uint64_t value = 0;
    if (!parseNumber(token, value))
      failLine(std::string("expected '") + expected + "', got '" + join(line) + "'");
    return value;
  }

  DataType dataType(std::string_view token) const {
    std::optional<DataType> type = parseDataType(token);
    if (!type)
      failLine("unknown data type '" + std::string(token) + "'");
    return *type;
  }

  uint64_t product(uint64_t a, uint64_t b) const {
    uint64_t result = 0;
    if (__builtin_mul_overflow(a, b, &result))
      failLine("value count overflows");
    return result;
  }

  // Values.

  /// Fails unless the rest of the file could hold `count` values: called before allocating for them.
  void checkRoom(DataType type, uint64_t count) const {
    uint64_t left = uint64_t(end_ - pos_);
    bool fits = binary_ ? binaryBytes(type, count) <= left : count <= left / 2 + 1;
    if (!fits)
      failLine(std::to_string(count) + " values declared but the file ends before them");
  }

  /// Reads `count` numeric values of `type` into out, converted to T.
  template <typename T> void readInto(DataType type, uint64_t count, T *out) {
    if (type.isString())
      failLine("expected numbers, got a string array");
    checkRoom(type, count);
    if (binary_) {
      sawBinary_ = true;
      auto bytes = reinterpret_cast<const uint8_t *>(pos_);
      if (type.kind == DataType::Kind::Bit) {
        for (uint64_t i = 0; i < count; ++i)
          out[i] = T((bytes[i / 8] >> (7 - i % 8)) & 1);
      } else {
        convertPacked(type.number, kSwapBigEndian, bytes, count, out);
      }
      pos_ += binaryBytes(type, count);
      return;
    }
    for (uint64_t i = 0; i < count; ++i) {
      std::string_view token = valueToken();
      if (token.empty())
        failToken("expected " + std::to_string(count) + " values, the file ends after " + std::to_string(i));
      if (!parseScalar(type.number, token.data(), token.data() + token.size(), out[i]))
        failToken("invalid number '" + std::string(token.substr(0, 40)) + "'");
    }
  }

  /// The `count` values in an Array of them: a std::vector or an UninitVector.
  template <typename Array> Array readValues(DataType type, uint64_t count) {
    checkRoom(type, count);
    Array values(count);
    readInto(type, count, values.data());
    return values;
  }

  void skipValues(DataType type, uint64_t count) {
    checkRoom(type, count);
    if (!type.isString()) {
      if (binary_) {
        sawBinary_ = true;
        pos_ += binaryBytes(type, count);
      } else {
        for (uint64_t i = 0; i < count; ++i)
          if (valueToken().empty())
            failToken("expected " + std::to_string(count) + " values, the file ends after " +
                      std::to_string(i));
      }
      return;
    }
    for (uint64_t i = 0; i < count; ++i) {
      if (pos_ == end_)
        failLine("expected " + std::to_string(count) + " strings, the file ends after " + std::to_string(i));
      if (!binary_) {
        rawLine(); // one string per line
        continue;
      }
      // Each binary string starts with its length; the top two bits of the first byte give the length's size.
      sawBinary_ = true;
      auto first = uint8_t(*pos_);
      int header = first >> 6 == 3 ? 1 : first >> 6 == 2 ? 2 : first >> 6 == 1 ? 4 : 8;
      if (header > end_ - pos_)
        failAt(where(pos_, 0), "string length runs past the end of the file");
      uint64_t length = first & 0x3f;
      for (int b = 1; b < header; ++b)
        length = length << 8 | uint8_t(pos_[b]);
      if (length > uint64_t(end_ - pos_ - header))
        failAt(where(pos_, 0),
               "string of " + std::to_string(length) + " bytes runs past the end of the file");
      pos_ += header + length;
    }
  }

  // Sections.

  void readSection(const Line &line) {
    std::string keyword = toUpper(line[0]);
    if (keyword == "POINTS")
      readPoints(line);
    else if (keyword == "CELLS")
      readCells(line);
    else if (keyword == "CELL_TYPES")
      readCellTypes(line);
    else if (keyword == "METADATA")
      skipMetadata();
    else if (keyword == "POINT_DATA" || keyword == "CELL_DATA")
      startAttributes(keyword, line);
    else if (keyword == "FIELD" && !inAttributes_)
      readField(line, false); // dataset-level field data: not per point or cell
    else if (inAttributes_)
      readAttribute(keyword, line);
    else
      failLine("unknown keyword '" + std::string(line[0]) + "'");
  }

  void readPoints(const Line &line) {
    if (line.size() != 3)
      failLine("expected 'POINTS n type', got '" + join(line) + "'");
    uint64_t n = count(line[1], line, "POINTS n type");
    DataType type = dataType(line[2]);
    uint64_t values = product(n, 3);
    checkRoom(type, values);
    static_assert(sizeof(Vec3f) == 3 * sizeof(float));
    grid_.points.resize(n);
    readInto(type, values, n ? &grid_.points[0].x : nullptr);
    for (uint64_t i = 0; i < n; ++i) {
      Vec3f p = grid_.points[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        failLine(
            "point " + std::to_string(i) +
            (type.number == ScalarType::Float64 ? " is out of float range or not finite" : " is not finite"));
    }
    lastComponents_ = 3;
  }

  void readCells(const Line &line) {
    if (line.size() != 3)
      failLine("expected 'CELLS n size', got '" + join(line) + "'");
    if (cellsWhere_.size())
      failLine("a second CELLS section");
    cellsWhere_ = where(lineStart_, lineNumber_);
    uint64_t first = count(line[1], line, "CELLS n size");
    uint64_t second = count(line[2], line, "CELLS n size");
    lastComponents_ = 1;

    if (!nextLineStartsWith("OFFSETS")) {
      readCellList(first, second);
      return;
    }
    Line next = readLine();
    // VTK 5.1 layout: CELLS nOffsets nConnectivity, then the two arrays.
    if (next.size() != 2)
      failLine("expected 'OFFSETS type', got '" + join(next) + "'");
    DataType offsetType = dataType(next[1]);
    if (!offsetType.isInteger())
      failLine("expected an integer type for OFFSETS");
    std::vector<int64_t> offsets = readValues<std::vector<int64_t>>(offsetType, first);
    std::string offsetsWhere = where(lineStart_, lineNumber_);
    Line connectivity = readLine();
    if (!connectivity.empty() && toUpper(connectivity[0]) == "METADATA") {
      skipMetadata();
      connectivity = readLine();
    }
    if (connectivity.size() != 2 || toUpper(connectivity[0]) != "CONNECTIVITY")
      failLine("expected 'CONNECTIVITY type', got '" + join(connectivity) + "'");
    DataType connectivityType = dataType(connectivity[1]);
    if (!connectivityType.isInteger())
      failLine("expected an integer type for CONNECTIVITY");
    grid_.connectivity = readValues<std::vector<int64_t>>(connectivityType, second);

    if (offsets.empty())
      offsets.push_back(0);
    if (offsets[0] != 0)
      failAt(offsetsWhere, "OFFSETS must start at 0, got " + std::to_string(offsets[0]));
    for (size_t i = 1; i < offsets.size(); ++i)
      if (offsets[i] < offsets[i - 1])
        failAt(offsetsWhere, "OFFSETS decrease at entry " + std::to_string(i));
    if (uint64_t(offsets.back()) != second)
      failAt(offsetsWhere, "OFFSETS end at " + std::to_string(offsets.back()) +
                               ", expected the CONNECTIVITY size " + std::to_string(second));
    grid_.offsets = std::move(offsets);
  }

  /// The layout before VTK 5.1: each cell is its vertex count followed by its vertices.
  void readCellList(uint64_t cells, uint64_t size) {
    std::vector<int64_t> list = readValues<std::vector<int64_t>>(numeric(ScalarType::Int32), size);
    if (cells > size)
      failAt(cellsWhere_, std::to_string(cells) + " cells cannot fit in " + std::to_string(size) + " values");
    grid_.offsets.assign(1, 0);
    grid_.offsets.reserve(cells + 1);
    grid_.connectivity.reserve(size - cells);
    uint64_t at = 0;
    for (uint64_t c = 0; c < cells; ++c) {
      int64_t n = at < size ? list[at] : -1;
      if (n < 0 || uint64_t(n) > size - at - 1)
        failAt(cellsWhere_,
               "cell " + std::to_string(c) + " runs past the CELLS size " + std::to_string(size));
      grid_.connectivity.insert(grid_.connectivity.end(), list.begin() + int64_t(at) + 1,
                                list.begin() + int64_t(at) + 1 + n);
      grid_.offsets.push_back(int64_t(grid_.connectivity.size()));
      at += uint64_t(n) + 1;
    }
    if (at != size)
      failAt(cellsWhere_,
             "CELLS declares " + std::to_string(size) + " values but its cells use " + std::to_string(at));
  }

  void readCellTypes(const Line &line) {
    if (line.size() != 2)
      failLine("expected 'CELL_TYPES n', got '" + join(line) + "'");
    if (typesWhere_.size())
      failLine("a second CELL_TYPES section");
    typesWhere_ = where(lineStart_, lineNumber_);
    uint64_t n = count(line[1], line, "CELL_TYPES n");
    std::vector<int64_t> codes = readValues<std::vector<int64_t>>(numeric(ScalarType::Int32), n);
    grid_.types.resize(n);
    for (uint64_t i = 0; i < n; ++i) {
      if (codes[i] < 0 || codes[i] > 255)
        failAt(typesWhere_, "cell type " + std::to_string(codes[i]) + " is not a VTK type code");
      grid_.types[i] = uint8_t(codes[i]);
    }
    lastComponents_ = 1;
  }

  /// METADATA after an array: optional COMPONENT_NAMES (one line per component, maybe empty) and
  /// INFORMATION keys, ended by a blank line.
  void skipMetadata() {
    while (pos_ < end_) {
      std::string_view text = rawLine();
      if (text.find_first_not_of(" \t") == std::string_view::npos)
        return;
      if (toUpper(text.substr(0, 15)) == "COMPONENT_NAMES")
        for (uint64_t i = 0; i < lastComponents_ && pos_ < end_; ++i)
          rawLine();
    }
  }

  void startAttributes(const std::string &keyword, const Line &line) {
    if (line.size() != 2)
      failLine("expected '" + keyword + " n', got '" + join(line) + "'");
    inAttributes_ = true;
    centering_ = keyword == "POINT_DATA" ? Centering::Point : Centering::Cell;
    tuples_ = count(line[1], line, (keyword + " n").c_str());
    uint64_t expected = centering_ == Centering::Point ? grid_.points.size() : grid_.offsets.size() - 1;
    if (tuples_ != expected)
      failLine(keyword + " " + std::to_string(tuples_) + " differs from the " +
               (centering_ == Centering::Point ? "point" : "cell") + " count " + std::to_string(expected));
  }

  void readAttribute(const std::string &keyword, const Line &line) {
    auto expectTokens = [&](size_t low, size_t high, const char *form) {
      if (line.size() < low || line.size() > high)
        failLine(std::string("expected '") + form + "', got '" + join(line) + "'");
    };
    if (keyword == "SCALARS") {
      expectTokens(3, 4, "SCALARS name type [numComponents]");
      uint64_t components = line.size() == 4 ? count(line[3], line, "SCALARS name type [numComponents]") : 1;
      DataType type = dataType(line[2]);
      if (nextLineStartsWith("LOOKUP_TABLE") && readLine().size() != 2)
        failLine("expected 'LOOKUP_TABLE name' after SCALARS");
      readArray(decodeName(line[1]), type, components);
    } else if (keyword == "VECTORS" || keyword == "NORMALS") {
      expectTokens(3, 3, "VECTORS name type");
      readArray(decodeName(line[1]), dataType(line[2]), 3);
    } else if (keyword == "TENSORS" || keyword == "TENSORS6") {
      expectTokens(3, 3, "TENSORS name type");
      readArray(decodeName(line[1]), dataType(line[2]), keyword == "TENSORS" ? 9 : 6);
    } else if (keyword == "TEXTURE_COORDINATES") {
      expectTokens(4, 4, "TEXTURE_COORDINATES name dim type");
      readArray(decodeName(line[1]), dataType(line[3]),
                count(line[2], line, "TEXTURE_COORDINATES name dim type"));
    } else if (keyword == "GLOBAL_IDS" || keyword == "PEDIGREE_IDS") {
      expectTokens(3, 3, "GLOBAL_IDS name type");
      readArray(decodeName(line[1]), dataType(line[2]), 1);
    } else if (keyword == "COLOR_SCALARS") {
      // Colors are not a quantity to render: skipped. Binary files store them as bytes, text as floats.
      expectTokens(3, 3, "COLOR_SCALARS name nValues");
      uint64_t values = product(tuples_, count(line[2], line, "COLOR_SCALARS name nValues"));
      skipValues(numeric(binary_ ? ScalarType::UInt8 : ScalarType::Float32), values);
    } else if (keyword == "LOOKUP_TABLE") {
      expectTokens(3, 3, "LOOKUP_TABLE name size");
      uint64_t values = product(count(line[2], line, "LOOKUP_TABLE name size"), 4);
      skipValues(numeric(binary_ ? ScalarType::UInt8 : ScalarType::Float32), values);
    } else if (keyword == "FIELD") {
      readField(line, true);
    } else {
      failLine("unknown keyword '" + std::string(line[0]) + "'");
    }
  }

  /// FIELD name nArrays, each array 'name numComponents numTuples type' and its values. `keep` is false for
  /// dataset-level field data, which is skipped.
  void readField(const Line &line, bool keep) {
    if (line.size() != 3)
      failLine("expected 'FIELD name numArrays', got '" + join(line) + "'");
    uint64_t arrays = count(line[2], line, "FIELD name numArrays");
    for (uint64_t i = 0; i < arrays;) {
      Line header = readLine();
      if (header.empty())
        failLine("expected " + std::to_string(arrays) + " FIELD arrays, the file ends after " +
                 std::to_string(i));
      if (header.size() == 1 && toUpper(header[0]) == "METADATA") {
        skipMetadata();
        continue;
      }
      ++i;
      if (header.size() == 1 && toUpper(header[0]) == "NULL_ARRAY")
        continue;
      if (header.size() != 4)
        failLine("expected 'arrayName numComponents numTuples type', got '" + join(header) + "'");
      uint64_t components = count(header[1], header, "arrayName numComponents numTuples type");
      uint64_t tuples = count(header[2], header, "arrayName numComponents numTuples type");
      DataType type = dataType(header[3]);
      if (!keep || type.isString()) {
        skipValues(type, product(components, tuples));
      } else {
        if (tuples != tuples_)
          failLine("FIELD array '" + std::string(header[0]) + "' has " + std::to_string(tuples) +
                   " tuples, expected " + std::to_string(tuples_));
        readArray(decodeName(header[0]), type, components);
      }
      lastComponents_ = components;
    }
  }

  /// One point or cell array becomes one field; several components become their Euclidean magnitude, as the
  /// renderer maps a single scalar. String arrays are skipped.
  void readArray(std::string name, DataType type, uint64_t components) {
    lastComponents_ = components;
    uint64_t values = product(tuples_, components);
    if (type.isString()) {
      skipValues(type, values);
      return;
    }
    if (components == 0)
      failLine("array '" + name + "' has no components");
    ScalarField field{std::move(name), centering_, readValues<UninitVector<float>>(type, values), components};
    if (components > 1) {
      for (uint64_t i = 0; i < tuples_; ++i) {
        double sum = 0.0;
        for (uint64_t c = 0; c < components; ++c)
          sum += double(field.values[i * components + c]) * field.values[i * components + c];
        field.values[i] = float(std::sqrt(sum));
      }
      field.values.resize(tuples_);
    }
    grid_.fields.push_back(std::move(field));
  }

  UnstructuredGrid finish() {
    uint64_t cells = grid_.offsets.size() - 1;
    if (grid_.types.size() != cells)
      failAt(typesWhere_.empty() ? cellsWhere_ : typesWhere_, "CELL_TYPES lists " +
                                                                  std::to_string(grid_.types.size()) +
                                                                  " cells, CELLS " + std::to_string(cells));
    // A polyhedron's entry is its face stream [nFaces, nPoints0, ids..., nPoints1, ids..., ...], in both
    // layouts: counts, not point indices, which decomposePolyhedra checks.
    PolyhedronFaces faces;
    for (uint64_t c = 0; c < cells; ++c)
      if (grid_.types[c] == kVtkPolyhedron)
        faces.appendStream(
            std::span(grid_.connectivity)
                .subspan(size_t(grid_.offsets[c]), size_t(grid_.offsets[c + 1] - grid_.offsets[c])),
            path_, "cell " + std::to_string(c));
    uint64_t points = grid_.points.size();
    for (uint64_t c = 0; c < cells; ++c) {
      if (grid_.types[c] == kVtkPolyhedron)
        continue;
      for (auto i = uint64_t(grid_.offsets[c]); i < uint64_t(grid_.offsets[c + 1]); ++i)
        if (grid_.connectivity[i] < 0 || uint64_t(grid_.connectivity[i]) >= points)
          failAt(cellsWhere_, "point index " + std::to_string(grid_.connectivity[i]) + " at entry " +
                                  std::to_string(i) + " is outside [0, " + std::to_string(points) + ")");
    }
    if (faces.polyhedronCount() > 0)
      decomposePolyhedra(grid_, faces, path_);
    return std::move(grid_);
  }

  std::string path_;
  FileBuffer file_;
  const char *begin_, *pos_, *end_;
  uint64_t line_ = 1;
  const char *lineStart_ = nullptr, *tokenStart_ = nullptr; ///< the last line and value token read
  uint64_t lineNumber_ = 1, tokenLine_ = 1;
  bool binary_ = false, sawBinary_ = false;

  UnstructuredGrid grid_;
  std::string cellsWhere_, typesWhere_; ///< where CELLS and CELL_TYPES were, for later errors
  bool inAttributes_ = false;           ///< after POINT_DATA or CELL_DATA
  Centering centering_ = Centering::Point;
  uint64_t tuples_ = 0;         ///< the POINT_DATA or CELL_DATA count
  uint64_t lastComponents_ = 1; ///< of the last array, for its METADATA
};

} // namespace

UnstructuredGrid readVtkLegacy(const std::string &path) { return LegacyReader(path).read(); }

} // namespace uvr
