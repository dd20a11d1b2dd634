// VTK XML UnstructuredGrid (.vtu) reader.
//
// Only the XML head is given to pugixml: appended raw data can hold any byte, so the text up to the '_'
// marker of <AppendedData> is parsed alone and each appended array is read at its `offset` after the marker.
#include "core/buffer.h"
#include "core/limits.h"
#include "io/file_buffer.h"
#include "io/mesh_io.h"
#include "io/scalar_type.h"
#include "mesh/polyhedra.h"
#include <uvr/error.h>

#ifdef UVR_HAVE_LIBDEFLATE
#include <libdeflate.h>
#else
#include <zlib.h>
#endif
#include <pugixml.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string_view>

namespace uvr {

namespace {

std::string numberText(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

bool multiplyOverflows(uint64_t a, uint64_t b, uint64_t &product) {
  return __builtin_mul_overflow(a, b, &product);
}

struct ScalarTypeName {
  std::string_view name;
  ScalarType type;
};

constexpr ScalarTypeName scalarTypeNames[] = {
    {"Int8", ScalarType::Int8},       {"UInt8", ScalarType::UInt8},   {"Int16", ScalarType::Int16},
    {"UInt16", ScalarType::UInt16},   {"Int32", ScalarType::Int32},   {"UInt32", ScalarType::UInt32},
    {"Int64", ScalarType::Int64},     {"UInt64", ScalarType::UInt64}, {"Float32", ScalarType::Float32},
    {"Float64", ScalarType::Float64},
};

/// Runs f(begin, end) over [0, n) in parallel chunks.
template <typename F> void parallelChunks(uint64_t n, F &&f) {
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n, 1 << 16),
                    [&](const tbb::blocked_range<uint64_t> &r) { f(r.begin(), r.end()); });
}

/// The first i in [0, n) with bad(i), or n.
template <typename Pred> uint64_t findFirst(uint64_t n, Pred &&bad) {
  return tbb::parallel_reduce(
      tbb::blocked_range<uint64_t>(0, n, 1 << 16), n,
      [&](const tbb::blocked_range<uint64_t> &r, uint64_t found) {
        for (uint64_t i = r.begin(); i < r.end() && i < found; ++i)
          if (bad(i))
            return i;
        return found;
      },
      [](uint64_t a, uint64_t b) { return std::min(a, b); });
}

/// Point indices narrowed to 32 bits as they are read (for at most 2^32 - 1 points), to be written and read
/// again in half the memory. An index outside [0, pointCount), as VTK's 64-bit value, becomes kOutside.
struct NarrowPointIndex {
  static constexpr uint32_t kOutside = UINT32_MAX;
  uint32_t pointCount;

  /// By the index's 32-bit halves (a negative one's high half is not 0) and selects without branches: the
  /// loop over 64-bit indices then vectorises, where SSE2 has no 64-bit compare.
  template <typename Value> uint32_t operator()(Value value) const {
    const auto index = uint64_t(static_cast<int64_t>(value));
    const auto low = uint32_t(index), high = uint32_t(index >> 32);
    return (high | uint32_t(low >= pointCount)) == 0 ? low : kOutside;
  }
};

/// A value check that every value passes.
struct AnyValue {
  template <typename Value> bool operator()(Value) const { return false; }
};

/// The least of the indices that threads note, or `none`.
class LeastIndex {
public:
  explicit LeastIndex(uint64_t none) : least_(none) {}
  void note(uint64_t index) {
    uint64_t least = least_.load(std::memory_order_relaxed);
    while (index < least && !least_.compare_exchange_weak(least, index, std::memory_order_relaxed)) {
    }
  }
  uint64_t least() const { return least_.load(); }

private:
  std::atomic<uint64_t> least_;
};

constexpr uint8_t base64Pad = 64, base64Space = 65, base64Invalid = 255;

constexpr std::array<uint8_t, 256> base64Table = [] {
  std::array<uint8_t, 256> table{};
  table.fill(base64Invalid);
  constexpr std::string_view alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t i = 0; i < alphabet.size(); ++i)
    table[uint8_t(alphabet[i])] = uint8_t(i);
  table['='] = base64Pad;
  for (char c : {' ', '\n', '\r', '\t'})
    table[uint8_t(c)] = base64Space;
  return table;
}();

/// Reads an array's bytes in order, from raw memory or from base64 text. The base64 text may be made of
/// several separately padded runs (VTK encodes a compressed array's header apart from its data) and may
/// hold whitespace.
class ByteStream {
public:
  ByteStream(const uint8_t *begin, const uint8_t *end, bool base64)
      : pos_(begin), end_(end), base64_(base64) {}

  /// Copies the next n bytes to dst; false (see problem()) if the input ends first or is not base64.
  bool read(uint8_t *dst, uint64_t n) {
    if (!base64_) {
      if (n > uint64_t(end_ - pos_))
        return fail("the file ends inside this array");
      std::memcpy(dst, pos_, n);
      pos_ += n;
      return true;
    }
    while (n > 0) {
      if (pendingBegin_ < pendingEnd_) {
        uint64_t k = std::min<uint64_t>(n, pendingEnd_ - pendingBegin_);
        std::memcpy(dst, pending_ + pendingBegin_, k);
        pendingBegin_ += int(k);
        dst += k;
        n -= k;
        continue;
      }
      while (n >= 3 && end_ - pos_ >= 4) {
        uint32_t a = base64Table[pos_[0]], b = base64Table[pos_[1]], c = base64Table[pos_[2]],
                 d = base64Table[pos_[3]];
        if ((a | b | c | d) >= 64)
          break;
        uint32_t bits = a << 18 | b << 12 | c << 6 | d;
        dst[0] = uint8_t(bits >> 16);
        dst[1] = uint8_t(bits >> 8);
        dst[2] = uint8_t(bits);
        dst += 3;
        n -= 3;
        pos_ += 4;
      }
      if (n > 0 && !decodeQuantum())
        return false;
    }
    return true;
  }

  /// More bytes than are left: sizes beyond this cannot be held by the input.
  uint64_t available() const {
    uint64_t left = uint64_t(end_ - pos_);
    return base64_ ? (left + 3) / 4 * 3 + uint64_t(pendingEnd_ - pendingBegin_) : left;
  }
  const uint8_t *position() const { return pos_; }
  const char *problem() const { return problem_; }

private:
  bool fail(const char *problem) {
    problem_ = problem;
    return false;
  }

  /// Decodes the next four symbols (skipping whitespace) into pending_.
  bool decodeQuantum() {
    uint8_t symbols[4];
    int count = 0;
    while (count < 4) {
      if (pos_ == end_)
        return fail(count == 0 ? "the base64 text ends inside this array"
                               : "base64 text ends inside a group of four");
      uint8_t symbol = base64Table[*pos_++];
      if (symbol == base64Invalid) {
        --pos_;
        return fail("invalid base64 character");
      }
      if (symbol != base64Space)
        symbols[count++] = symbol;
    }
    int bytes = symbols[3] != base64Pad ? 3 : symbols[2] != base64Pad ? 2 : 1;
    bool misplacedPad = symbols[0] == base64Pad || symbols[1] == base64Pad ||
                        (symbols[2] == base64Pad && symbols[3] != base64Pad);
    if (misplacedPad)
      return fail("misplaced base64 padding '='");
    uint32_t bits = 0;
    for (int i = 0; i < 4; ++i)
      bits = bits << 6 | (symbols[i] == base64Pad ? 0u : symbols[i]);
    pending_[0] = uint8_t(bits >> 16);
    pending_[1] = uint8_t(bits >> 8);
    pending_[2] = uint8_t(bits);
    pendingBegin_ = 0;
    pendingEnd_ = bytes;
    return true;
  }

  const uint8_t *pos_, *end_;
  bool base64_;
  uint8_t pending_[3] = {};
  int pendingBegin_ = 0, pendingEnd_ = 0;
  const char *problem_ = "";
};

enum class Format { Ascii, Binary, Appended };

/// One <DataArray>, located but not decoded.
struct ArrayInfo {
  std::string name;
  ScalarType type = ScalarType::Float32;
  uint64_t components = 1;
  Format format = Format::Ascii;
  uint64_t offset = 0;   ///< appended: bytes (raw) or characters (base64) after the '_' marker
  std::string_view text; ///< ascii and binary: the element's text
  uint64_t position = 0; ///< the element's byte in the file
};

/// Where an array's bytes come from once its header is checked: contiguous bytes, or zlib blocks of them.
struct Payload {
  struct Block {
    uint64_t source, sourceSize, target, targetSize;
  };
  const uint8_t *data = nullptr; ///< the uncompressed bytes, or the concatenated zlib blocks
  Buffer<uint8_t> storage;       ///< base64-decoded bytes behind `data`
  uint64_t size = 0;             ///< uncompressed bytes
  std::vector<Block> blocks;     ///< empty when uncompressed
  uint64_t position = 0;         ///< byte in the file, for errors
};

/// zlib never inflates more than about 1032:1, so a header claiming more is corrupt (and must not be
/// allocated).
constexpr uint64_t maxZlibRatio = 1032;

/// The first corrupt zlib block by index, among blocks inflated in parallel: so that the error does not
/// depend on thread timing.
class FirstCorruptBlock {
public:
  void note(uint64_t block, const char *problem) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (block < block_) {
      block_ = block;
      problem_ = problem;
    }
  }
  bool found() const { return block_ != UINT64_MAX; }
  uint64_t block() const { return block_; }
  const char *problem() const { return problem_; }

private:
  std::mutex mutex_;
  uint64_t block_ = UINT64_MAX;
  const char *problem_ = "";
};

/// Inflates one zlib block of known sizes; returns what is wrong with it, or nullptr.
const char *inflateBlock(const uint8_t *source, uint64_t sourceSize, uint8_t *target, uint64_t targetSize) {
#ifdef UVR_HAVE_LIBDEFLATE
  thread_local std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor *)> decompressor(
      libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
  size_t inflated = 0;
  const libdeflate_result result =
      libdeflate_zlib_decompress(decompressor.get(), source, sourceSize, target, targetSize, &inflated);
  if (result == LIBDEFLATE_BAD_DATA)
    return "invalid zlib data";
  if (result == LIBDEFLATE_INSUFFICIENT_SPACE)
    return "it inflates to more bytes than its header says";
#else
  uLongf inflated = targetSize;
  const int result = ::uncompress(target, &inflated, source, sourceSize);
  if (result == Z_BUF_ERROR && inflated == targetSize)
    return "it inflates to more bytes than its header says";
  if (result != Z_OK)
    return "invalid zlib data";
#endif
  return inflated == targetSize ? nullptr : "it inflates to fewer bytes than its header says";
}

/// An UnstructuredGrid whose cell arrays, the largest, are Buffers: decoded straight into them, and viewed in
/// place by buildMesh.
struct VtuGrid {
  UninitVector<Vec3f> points;
  Buffer<int64_t> offsets;       ///< cell count + 1 entries, offsets[0] == 0
  Buffer<uint32_t> connectivity; ///< narrowed as it is read (see NarrowPointIndex)
  Buffer<uint8_t> types;
  std::vector<ScalarField> fields;
  PolyhedronCounts polyhedra; ///< already decomposed into the cells above
};

class VtuReader {
public:
  explicit VtuReader(const std::string &path) : path_(path), file_(path) {}

  VtuGrid read() {
    parseXml();
    pugi::xml_node root = doc_.document_element();
    if (std::string_view(root.name()) != "VTKFile")
      fail(position(root), "expected a <VTKFile> root element, got <" + std::string(root.name()) + ">");
    readFileAttributes(root);
    std::string_view type = root.attribute("type").value();
    pugi::xml_node grid = root.child("UnstructuredGrid");
    if (type != "UnstructuredGrid" || !grid)
      fail(position(root),
           "unsupported dataset type '" + std::string(type) + "' (expected UnstructuredGrid)");

    std::vector<VtuGrid> pieces;
    std::vector<uint64_t> piecePositions;
    for (pugi::xml_node piece : grid.children("Piece")) {
      pieces.push_back(readPiece(piece));
      piecePositions.push_back(position(piece));
    }
    if (pieces.empty())
      fail(position(grid), "expected at least one <Piece> in <UnstructuredGrid>");
    return merge(std::move(pieces), piecePositions);
  }

private:
  [[noreturn]] void fail(uint64_t byte, const std::string &what) const {
    throw Error(path_, "byte " + std::to_string(byte), what);
  }
  [[noreturn]] void fail(const ArrayInfo &array, uint64_t byte, const std::string &what) const {
    fail(byte, "DataArray '" + array.name + "': " + what);
  }

  const char *fileChars() const { return reinterpret_cast<const char *>(file_.data()); }

  uint64_t position(pugi::xml_node node) const {
    return uint64_t(std::max<ptrdiff_t>(node.offset_debug(), 0));
  }
  uint64_t position(const char *xmlText) const { return uint64_t(xmlText - xmlBase_); }

  void parseXml() {
    std::string_view all(fileChars(), file_.size());
    constexpr unsigned options = pugi::parse_default & ~pugi::parse_eol; // keeps text where it is in the file
    size_t tag = all.find("<AppendedData");
    pugi::xml_parse_result result;
    if (tag == std::string_view::npos) {
      head_ = std::string(all); // pugixml writes into the text it parses, and the mapping is read-only
      xmlBase_ = head_.data();
      result = doc_.load_buffer_inplace(head_.data(), head_.size(), options, pugi::encoding_utf8);
    } else {
      size_t tagEnd = all.find('>', tag);
      if (tagEnd == std::string_view::npos)
        fail(tag, "unterminated <AppendedData> tag");
      size_t marker = tagEnd + 1;
      while (marker < all.size() && isSpace(all[marker]))
        ++marker;
      if (marker == all.size() || all[marker] != '_')
        fail(marker, "expected '_' at the start of the appended data");
      appended_ = file_.data() + marker + 1;
      head_ = std::string(all.substr(0, tagEnd + 1)) + "</AppendedData></VTKFile>";
      xmlBase_ = head_.data();
      result = doc_.load_buffer_inplace(head_.data(), head_.size(), options, pugi::encoding_utf8);
      if (result && all[tagEnd - 1] == '/')
        fail(tag, "<AppendedData/> is empty");
    }
    if (!result)
      fail(uint64_t(std::max<ptrdiff_t>(result.offset, 0)),
           std::string("malformed XML: ") + result.description());
    if (appended_) {
      pugi::xml_node appendedNode = doc_.document_element().child("AppendedData");
      std::string_view encoding = appendedNode.attribute("encoding").value();
      if (encoding != "raw" && encoding != "base64")
        fail(position(appendedNode),
             "unsupported <AppendedData> encoding '" + std::string(encoding) + "' (expected raw or base64)");
      appendedBase64_ = encoding == "base64";
    }
  }

  void readFileAttributes(pugi::xml_node root) {
    std::string_view byteOrder = root.attribute("byte_order").as_string("LittleEndian");
    if (byteOrder != "LittleEndian" && byteOrder != "BigEndian")
      fail(position(root), "unsupported byte_order '" + std::string(byteOrder) + "'");
    swap_ = (byteOrder == "BigEndian") != (std::endian::native == std::endian::big);

    std::string_view headerType = root.attribute("header_type").as_string("UInt32");
    if (headerType != "UInt32" && headerType != "UInt64")
      fail(position(root),
           "unsupported header_type '" + std::string(headerType) + "' (expected UInt32 or UInt64)");
    headerBytes_ = headerType == "UInt32" ? 4 : 8;

    std::string_view compressor = root.attribute("compressor").value();
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
      fail(position(root),
           "unsupported compressor '" + std::string(compressor) + "' (only vtkZLibDataCompressor)");
    compressed_ = !compressor.empty();
    // Summed over every array, not checked per array: arrays may share one appended offset. Binary values
    // widen at most 8 times as they are decoded (ascii text is bounded by its own length).
    inflation_ = InflationBound(path_, file_.size(), compressed_ ? kMaxDeflateRatio : 8);
  }

  uint64_t countAttribute(pugi::xml_node node, const char *name) const {
    std::string_view text = trim(node.attribute(name).value());
    uint64_t value = 0;
    if (!parseNumber(text, value))
      fail(position(node), std::string("expected a non-negative integer ") + name + "=\"...\" on <" +
                               node.name() + ">, got '" + node.attribute(name).value() + "'");
    return value;
  }

  ArrayInfo arrayInfo(pugi::xml_node node) const {
    ArrayInfo array;
    array.name = node.attribute("Name").value();
    array.position = position(node);
    std::string_view type = node.attribute("type").value();
    auto known = std::find_if(std::begin(scalarTypeNames), std::end(scalarTypeNames),
                              [&](const ScalarTypeName &t) { return t.name == type; });
    if (known == std::end(scalarTypeNames))
      fail(array, array.position, "unsupported type '" + std::string(type) + "'");
    array.type = known->type;
    if (node.attribute("NumberOfComponents")) {
      array.components = countAttribute(node, "NumberOfComponents");
      if (array.components == 0 || array.components > (1u << 16))
        fail(array, array.position, "NumberOfComponents must be in 1..65536");
    }
    std::string_view format = node.attribute("format").value();
    if (format == "appended") {
      if (!appended_)
        fail(array, array.position, "format=\"appended\" but the file has no <AppendedData>");
      array.format = Format::Appended;
      array.offset = countAttribute(node, "offset");
      return array;
    }
    if (format != "ascii" && format != "binary")
      fail(array, array.position, "unsupported format '" + std::string(format) + "'");
    array.format = format == "ascii" ? Format::Ascii : Format::Binary;
    for (pugi::xml_node child : node.children()) {
      if (child.type() == pugi::node_pcdata) {
        array.text = child.value();
        break;
      }
    }
    if (array.text.empty())
      array.text = std::string_view(xmlBase_ + array.position, 0);
    return array;
  }

  /// Checks an array's header against the file and `bytes` (what the caller expects) before anything is
  /// allocated from it.
  Payload locate(const ArrayInfo &array, uint64_t bytes) const {
    const uint8_t *begin, *end;
    bool base64 = true;
    if (array.format == Format::Binary) {
      begin = reinterpret_cast<const uint8_t *>(array.text.data());
      end = begin + array.text.size();
    } else {
      end = file_.data() + file_.size();
      if (array.offset > uint64_t(end - appended_))
        fail(array, array.position,
             "offset " + std::to_string(array.offset) + " is past the end of the file");
      begin = appended_ + array.offset;
      base64 = appendedBase64_;
    }
    const uint8_t *fileStart =
        array.format == Format::Binary ? reinterpret_cast<const uint8_t *>(xmlBase_) : file_.data();
    ByteStream stream(begin, end, base64);
    const std::string endsFirst =
        array.format == Format::Binary ? " but its text ends first" : " but the file ends first";
    auto here = [&] { return uint64_t(stream.position() - fileStart); };
    auto readOrFail = [&](uint8_t *dst, uint64_t n) {
      if (!stream.read(dst, n))
        fail(array, here(), stream.problem());
    };
    auto word = [&] {
      uint8_t raw[8];
      readOrFail(raw, uint64_t(headerBytes_));
      return headerBytes_ == 4 ? uint64_t(loadValue<uint32_t>(raw, swap_)) : loadValue<uint64_t>(raw, swap_);
    };

    Payload payload;
    payload.position = here();
    if (!compressed_) {
      payload.size = word();
      if (payload.size != bytes)
        fail(array, payload.position,
             "holds " + std::to_string(payload.size) + " bytes, expected " + std::to_string(bytes));
      if (payload.size > stream.available())
        fail(array, here(), std::to_string(payload.size) + " bytes declared" + endsFirst);
      if (base64) {
        payload.storage = Buffer<uint8_t>(payload.size);
        readOrFail(payload.storage.data(), payload.size);
        payload.data = payload.storage.data();
      } else {
        payload.data = stream.position();
      }
      return payload;
    }

    uint64_t blockCount = word(), blockSize = word(), lastSize = word();
    if (blockCount > stream.available() / uint64_t(headerBytes_))
      fail(array, here(), std::to_string(blockCount) + " compressed blocks declared" + endsFirst);
    if (lastSize > blockSize)
      fail(array, payload.position, "last block size exceeds the block size");
    uint64_t total = 0;
    if (blockCount > 0 && (multiplyOverflows(blockCount - 1, blockSize, total) ||
                           __builtin_add_overflow(total, lastSize ? lastSize : blockSize, &total)))
      fail(array, payload.position, "compression header sizes overflow");
    if (total != bytes)
      fail(array, payload.position,
           "inflates to " + std::to_string(total) + " bytes, expected " + std::to_string(bytes));
    payload.size = total;
    payload.blocks.resize(blockCount);
    uint64_t compressedTotal = 0;
    for (uint64_t i = 0; i < blockCount; ++i) {
      Payload::Block &block = payload.blocks[i];
      block.source = compressedTotal;
      block.sourceSize = word();
      block.target = i * blockSize;
      block.targetSize = i + 1 == blockCount && lastSize ? lastSize : blockSize;
      if (__builtin_add_overflow(compressedTotal, block.sourceSize, &compressedTotal) ||
          block.targetSize / maxZlibRatio > block.sourceSize)
        fail(array, payload.position, "compressed block " + std::to_string(i) + " has an impossible size");
    }
    if (compressedTotal > stream.available())
      fail(array, here(), std::to_string(compressedTotal) + " compressed bytes declared" + endsFirst);
    payload.position = here();
    if (base64) {
      payload.storage = Buffer<uint8_t>(compressedTotal);
      readOrFail(payload.storage.data(), compressedTotal);
      payload.data = payload.storage.data();
    } else {
      payload.data = stream.position();
    }
    return payload;
  }

  /// Writes the payload's uncompressed bytes to dst, inflating zlib blocks in parallel (with libdeflate: the
  /// blocks' sizes are known, which is what its one-shot decompressor needs).
  void decode(const ArrayInfo &array, const Payload &payload, uint8_t *dst) const {
    if (payload.blocks.empty()) {
      std::memcpy(dst, payload.data, payload.size);
      return;
    }
    FirstCorruptBlock corrupt;
    tbb::parallel_for(size_t(0), payload.blocks.size(), [&](size_t i) {
      const Payload::Block &block = payload.blocks[i];
      if (const char *problem = inflateBlock(payload.data + block.source, block.sourceSize,
                                             dst + block.target, block.targetSize))
        corrupt.note(i, problem);
    });
    failIfCorrupt(array, payload, corrupt);
  }

  void failIfCorrupt(const ArrayInfo &array, const Payload &payload, const FirstCorruptBlock &corrupt) const {
    if (corrupt.found())
      fail(array, payload.position + payload.blocks[corrupt.block()].source,
           "zlib block " + std::to_string(corrupt.block()) + " is corrupt (" + corrupt.problem() + ")");
  }

  /// Calls use(bytes, first, n) in parallel on runs of the payload's uncompressed bytes, each holding values
  /// [first, first + n) of `valueBytes`. zlib blocks are inflated one by one into a buffer of the task's, so
  /// that each run is converted while in cache, not written to memory and read back; blocks that split a
  /// value (VTK writes none) are inflated whole first.
  template <typename Use>
  void forEachRun(const ArrayInfo &array, const Payload &payload, uint64_t valueBytes, Use &&use) const {
    const std::vector<Payload::Block> &blocks = payload.blocks;
    const bool splitValues = std::any_of(blocks.begin(), blocks.end(), [&](const Payload::Block &block) {
      return block.target % valueBytes != 0 || block.targetSize % valueBytes != 0;
    });
    if (blocks.empty() || splitValues) {
      Buffer<uint8_t> inflated;
      const uint8_t *bytes = payload.data;
      if (!blocks.empty()) {
        inflated = Buffer<uint8_t>(payload.size);
        decode(array, payload, inflated.data());
        bytes = inflated.data();
      }
      parallelChunks(payload.size / valueBytes, [&](uint64_t begin, uint64_t end) {
        use(bytes + begin * valueBytes, begin, end - begin);
      });
      return;
    }
    FirstCorruptBlock corrupt;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks.size()), [&](const tbb::blocked_range<size_t> &r) {
      uint64_t largest = 0;
      for (size_t i = r.begin(); i < r.end(); ++i)
        largest = std::max(largest, blocks[i].targetSize);
      Buffer<uint8_t> run(largest);
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const Payload::Block &block = blocks[i];
        if (const char *problem =
                inflateBlock(payload.data + block.source, block.sourceSize, run.data(), block.targetSize))
          corrupt.note(i, problem);
        else
          use(run.data(), block.target / valueBytes, block.targetSize / valueBytes);
      }
    });
    failIfCorrupt(array, payload, corrupt);
  }

  template <typename T, typename To>
  void parseAscii(const ArrayInfo &array, uint64_t count, T *out, const To &to) const {
    const char *p = array.text.data(), *end = p + array.text.size();
    for (uint64_t i = 0; i < count; ++i) {
      p = skipSpace(p, end);
      if (p == end)
        fail(array, position(p), "holds " + std::to_string(i) + " values, expected " + std::to_string(count));
      const char *stop = tokenEnd(p, end);
      if (!parseScalar(array.type, p, stop, out[i], to))
        fail(array, position(p), "invalid number '" + std::string(p, std::min<size_t>(stop - p, 40)) + "'");
      p = stop;
    }
    p = skipSpace(p, end);
    if (p != end)
      fail(array, position(p), "holds more than the expected " + std::to_string(count) + " values");
  }

  /// Checks that the array can hold `count` values (throwing if not): call before allocating for them.
  Payload prepare(const ArrayInfo &array, uint64_t count) const {
    if (array.format == Format::Ascii) {
      if (count > array.text.size() / 2 + 1)
        fail(array, position(array.text.data()),
             "expected " + std::to_string(count) + " values but its text is too short to hold them");
      return {};
    }
    uint64_t bytes = 0;
    if (multiplyOverflows(count, scalarSize(array.type), bytes))
      fail(array, array.position, "expected value count overflows");
    Payload payload = locate(array, bytes); // its header checked first: it allocates only what the file holds
    inflation_.claim(bytes, "byte " + std::to_string(array.position), "DataArray '" + array.name + "'");
    return payload;
  }

  /// Writes the array's `count` values (as prepared) to out, converted to T by `to`. Returns the index of the
  /// first value that `bad` flags, or count; runs of converted values are checked as they are written, while
  /// in cache.
  template <typename T, typename To = CastTo<T>, typename Bad = AnyValue>
  uint64_t fill(const ArrayInfo &array, const Payload &payload, uint64_t count, T *out, const To &to = {},
                const Bad &bad = {}) const {
    const bool direct = std::is_same_v<To, CastTo<T>> && array.type == scalarTypeOf<T>() && !swap_;
    if (array.format == Format::Ascii || direct) {
      if (array.format == Format::Ascii)
        parseAscii(array, count, out, to);
      else
        decode(array, payload, reinterpret_cast<uint8_t *>(out));
      if constexpr (std::is_same_v<Bad, AnyValue>)
        return count;
      else
        return findFirst(count, [&](uint64_t i) { return bad(out[i]); });
    }
    LeastIndex firstBad(count);
    forEachRun(array, payload, scalarSize(array.type), [&](const uint8_t *bytes, uint64_t first, uint64_t n) {
      convertPacked(array.type, swap_, bytes, n, out + first, to);
      // Whether any value is bad, without an early exit, so that the loop vectorises; which one, only then.
      unsigned anyBad = 0; // not a bool, whose |= does not vectorise
      for (uint64_t i = first; i < first + n; ++i)
        anyBad |= unsigned(bad(out[i]));
      if (anyBad)
        firstBad.note(uint64_t(std::find_if(out + first, out + first + n, bad) - out));
    });
    return firstBad.least();
  }

  /// The array's `count` values in an Array of them: an UninitVector or a Buffer.
  template <typename Array> Array readValues(const ArrayInfo &array, uint64_t count) const {
    Payload payload = prepare(array, count);
    Array values(count);
    fill(array, payload, count, values.data());
    return values;
  }

  ArrayInfo cellArray(pugi::xml_node cells, std::string_view name, pugi::xml_node piece) const {
    for (pugi::xml_node node : cells.children("DataArray")) {
      if (node.attribute("Name").value() == name) {
        ArrayInfo array = arrayInfo(node);
        if (!isInteger(array.type) || array.components != 1)
          fail(array, array.position, "expected one integer component");
        return array;
      }
    }
    fail(position(cells ? cells : piece),
         "expected <Cells> with a DataArray named '" + std::string(name) + "'");
  }

  VtuGrid readPiece(pugi::xml_node piece) const {
    uint64_t pointCount = countAttribute(piece, "NumberOfPoints");
    uint64_t cellCount = countAttribute(piece, "NumberOfCells");
    VtuGrid grid;

    if (pointCount > 0) {
      pugi::xml_node node = piece.child("Points").child("DataArray");
      if (!node)
        fail(position(piece), "expected <Points> with a DataArray");
      ArrayInfo array = arrayInfo(node);
      if (array.components != 3)
        fail(array, array.position, "points need 3 components, got " + std::to_string(array.components));
      uint64_t values = 0;
      if (multiplyOverflows(pointCount, 3, values))
        fail(position(piece), "NumberOfPoints overflows");
      static_assert(sizeof(Vec3f) == 3 * sizeof(float));
      Payload payload = prepare(array, values);
      grid.points.resize(pointCount);
      const uint64_t bad = fill(array, payload, values, &grid.points[0].x, CastTo<float>{},
                                [](float x) { return !std::isfinite(x); });
      if (bad < values) { // a finite Float64 beyond float's range is named so, read again as doubles
        inflation_ = InflationBound(path_, UINT64_MAX / 2, 1);
        const double value = readValues<Buffer<double>>(array, values)[bad];
        fail(array, array.position,
             "point " + std::to_string(bad / 3) +
                 (std::isfinite(value) ? " is out of float range (" + numberText(value) + ")"
                                       : " is not finite"));
      }
    }

    grid.offsets = Buffer<int64_t>(1);
    grid.offsets[0] = 0;
    if (cellCount > 0) {
      pugi::xml_node cells = piece.child("Cells");
      ArrayInfo offsets = cellArray(cells, "offsets", piece);
      ArrayInfo connectivity = cellArray(cells, "connectivity", piece);
      ArrayInfo types = cellArray(cells, "types", piece);

      // The file stores each cell's end; the grid also keeps the leading zero.
      Payload payload = prepare(offsets, cellCount);
      grid.offsets = Buffer<int64_t>(cellCount + 1);
      grid.offsets[0] = 0;
      fill(offsets, payload, cellCount, grid.offsets.data() + 1);
      uint64_t bad = findFirst(cellCount, [&](uint64_t i) { return grid.offsets[i + 1] < grid.offsets[i]; });
      if (bad < cellCount)
        fail(offsets, offsets.position, "offsets decrease (or start below 0) at cell " + std::to_string(bad));

      const uint64_t connectivityCount = uint64_t(grid.offsets[cellCount]);
      if (pointCount > NarrowPointIndex::kOutside)
        throw Error(path_, "", "more than 2^32 points are not supported"); // as buildMesh says
      Payload indices = prepare(connectivity, connectivityCount);
      grid.connectivity = Buffer<uint32_t>(connectivityCount);
      bad = fill(connectivity, indices, connectivityCount, grid.connectivity.data(),
                 NarrowPointIndex{uint32_t(pointCount)},
                 [](uint32_t index) { return index == NarrowPointIndex::kOutside; });
      if (bad < connectivityCount) { // named by its value in the file, read again
        inflation_ = InflationBound(path_, UINT64_MAX / 2, 1);
        fail(connectivity, connectivity.position,
             "point index " +
                 std::to_string(readValues<Buffer<int64_t>>(connectivity, connectivityCount)[bad]) +
                 " at entry " + std::to_string(bad) + " is outside [0, " + std::to_string(pointCount) + ")");
      }

      if (types.type == ScalarType::UInt8) {
        grid.types = readValues<Buffer<uint8_t>>(types, cellCount);
      } else {
        Buffer<int64_t> codes = readValues<Buffer<int64_t>>(types, cellCount);
        bad = findFirst(cellCount, [&](uint64_t i) { return codes[i] < 0 || codes[i] > 255; });
        if (bad < cellCount)
          fail(types, types.position, "cell type " + std::to_string(codes[bad]) + " is not a VTK type code");
        grid.types = Buffer<uint8_t>(cellCount);
        std::copy(codes.begin(), codes.end(), grid.types.begin());
      }
    }

    readFields(piece.child("PointData"), Centering::Point, pointCount, grid.fields);
    readFields(piece.child("CellData"), Centering::Cell, cellCount, grid.fields);
    if (std::find(grid.types.begin(), grid.types.end(), kVtkPolyhedron) != grid.types.end())
      decompose(grid, readPolyhedra(piece.child("Cells"), grid.types));
    return grid;
  }

  std::optional<ArrayInfo> optionalCellArray(pugi::xml_node cells, std::string_view name) const {
    for (pugi::xml_node node : cells.children("DataArray"))
      if (node.attribute("Name").value() == name)
        return cellArray(cells, name, cells);
    return std::nullopt;
  }

  /// The faces of a piece's polyhedra: VTK's `faces` (each polyhedron's face stream) and `faceoffsets` (where
  /// each cell's stream ends, -1 for other cells), or VTK 9.4's `face_connectivity` and `face_offsets` (the
  /// faces) with `polyhedron_to_faces` and `polyhedron_offsets` (each cell's faces; offsets are ends, as the
  /// cells' are). Every count is checked against the file before it is allocated (see prepare).
  PolyhedronFaces readPolyhedra(pugi::xml_node cells, const Buffer<uint8_t> &types) const {
    const uint64_t cellCount = types.size();
    PolyhedronFaces faces;
    auto readInts = [&](const ArrayInfo &array, uint64_t count) {
      return readValues<std::vector<int64_t>>(array, count);
    };
    if (const std::optional<ArrayInfo> faceOffsets = optionalCellArray(cells, "faceoffsets")) {
      const std::optional<ArrayInfo> stream = optionalCellArray(cells, "faces");
      if (!stream)
        fail(position(cells), "polyhedra with 'faceoffsets' but no 'faces' array");
      const std::vector<int64_t> ends = readInts(*faceOffsets, cellCount);
      int64_t end = 0;
      for (uint64_t c = 0; c < cellCount; ++c) {
        if (types[c] != kVtkPolyhedron)
          continue;
        if (ends[c] <= end)
          fail(*faceOffsets, faceOffsets->position,
               "face offset " + std::to_string(ends[c]) + " of polyhedral cell " + std::to_string(c) +
                   " does not follow the previous one (" + std::to_string(end) + ")");
        end = ends[c];
      }
      const std::vector<int64_t> values = readInts(*stream, uint64_t(end));
      int64_t begin = 0;
      for (uint64_t c = 0; c < cellCount; ++c) {
        if (types[c] != kVtkPolyhedron)
          continue;
        faces.appendStream(std::span(values).subspan(size_t(begin), size_t(ends[c] - begin)), path_,
                           "cell " + std::to_string(c));
        begin = ends[c];
      }
      return faces;
    }
    const std::optional<ArrayInfo> cellFaceOffsets = optionalCellArray(cells, "polyhedron_offsets");
    const std::optional<ArrayInfo> cellFaces = optionalCellArray(cells, "polyhedron_to_faces");
    const std::optional<ArrayInfo> faceOffsets = optionalCellArray(cells, "face_offsets");
    const std::optional<ArrayInfo> faceConnectivity = optionalCellArray(cells, "face_connectivity");
    if (!cellFaceOffsets || !cellFaces || !faceOffsets || !faceConnectivity)
      fail(position(cells), "polyhedra (cell type 42) without their faces: expected 'faces' and "
                            "'faceoffsets', or 'face_connectivity', 'face_offsets', 'polyhedron_to_faces' "
                            "and 'polyhedron_offsets'");
    const std::vector<int64_t> cellEnds = readInts(*cellFaceOffsets, cellCount);
    int64_t end = 0;
    for (uint64_t c = 0; c < cellCount; ++c) {
      const bool polyhedron = types[c] == kVtkPolyhedron;
      if (polyhedron ? cellEnds[c] <= end : cellEnds[c] != end)
        fail(*cellFaceOffsets, cellFaceOffsets->position,
             "offset " + std::to_string(cellEnds[c]) + " of cell " + std::to_string(c) +
                 (polyhedron ? " does not follow the previous one (" : " differs from the previous one (") +
                 std::to_string(end) + ")");
      end = cellEnds[c];
      if (polyhedron)
        faces.cellOffsets.push_back(end);
    }
    faces.faceIds = readInts(*cellFaces, uint64_t(end));
    // The faces' count is not stored: the ids say how many there are.
    int64_t faceCount = 0;
    for (int64_t id : faces.faceIds) {
      if (id < 0)
        fail(*cellFaces, cellFaces->position, "face id " + std::to_string(id) + " is negative");
      faceCount = std::max(faceCount, id + 1);
    }
    const std::vector<int64_t> faceEnds = readInts(*faceOffsets, uint64_t(faceCount));
    for (size_t f = 0; f < faceEnds.size(); ++f)
      if (faceEnds[f] < faces.faceOffsets.back() + 3)
        fail(*faceOffsets, faceOffsets->position,
             "face " + std::to_string(f) + " ends at " + std::to_string(faceEnds[f]) +
                 ": fewer than 3 points, or offsets decreasing");
      else
        faces.faceOffsets.push_back(faceEnds[f]);
    faces.facePoints = readInts(*faceConnectivity, uint64_t(faces.faceOffsets.back()));
    return faces;
  }

  /// Replaces the piece's polyhedra by tetrahedra and pyramids (see decomposePolyhedra).
  void decompose(VtuGrid &grid, const PolyhedronFaces &faces) const {
    UnstructuredGrid all{std::move(grid.points),
                         {grid.offsets.begin(), grid.offsets.end()},
                         {grid.connectivity.begin(), grid.connectivity.end()},
                         {grid.types.begin(), grid.types.end()},
                         std::move(grid.fields),
                         {}};
    decomposePolyhedra(all, faces, path_);
    grid.points = std::move(all.points);
    grid.fields = std::move(all.fields);
    grid.polyhedra = all.polyhedra;
    grid.offsets = Buffer<int64_t>(all.offsets.size());
    std::copy(all.offsets.begin(), all.offsets.end(), grid.offsets.begin());
    grid.connectivity = Buffer<uint32_t>(all.connectivity.size());
    std::copy(all.connectivity.begin(), all.connectivity.end(), grid.connectivity.begin());
    grid.types = Buffer<uint8_t>(all.types.size());
    std::copy(all.types.begin(), all.types.end(), grid.types.begin());
  }

  /// Every numeric array becomes one field; several components become their Euclidean magnitude, as the
  /// renderer maps a single scalar. String arrays are skipped.
  void readFields(pugi::xml_node data, Centering centering, uint64_t tuples,
                  std::vector<ScalarField> &fields) const {
    for (pugi::xml_node node : data.children("DataArray")) {
      if (std::string_view(node.attribute("type").value()) == "String")
        continue;
      ArrayInfo array = arrayInfo(node);
      uint64_t count = 0;
      if (multiplyOverflows(tuples, array.components, count))
        fail(array, array.position, "value count overflows");
      ScalarField field{array.name, centering, readValues<UninitVector<float>>(array, count),
                        array.components};
      if (array.components > 1) {
        UninitVector<float> magnitude(tuples);
        uint64_t components = array.components;
        parallelChunks(tuples, [&](uint64_t begin, uint64_t end) {
          for (uint64_t i = begin; i < end; ++i) {
            double sum = 0.0;
            for (uint64_t c = 0; c < components; ++c)
              sum += double(field.values[i * components + c]) * field.values[i * components + c];
            magnitude[i] = float(std::sqrt(sum));
          }
        });
        field.values = std::move(magnitude);
      }
      fields.push_back(std::move(field));
    }
  }

  /// Concatenates pieces: point indices and offsets of later pieces are shifted past the earlier ones.
  VtuGrid merge(std::vector<VtuGrid> pieces, const std::vector<uint64_t> &positions) const {
    if (pieces.size() == 1)
      return std::move(pieces[0]);
    uint64_t pointCount = 0, cellCount = 0, connectivityCount = 0;
    VtuGrid grid;
    for (size_t p = 0; p < pieces.size(); ++p) {
      const VtuGrid &piece = pieces[p];
      bool sameFields = piece.fields.size() == pieces[0].fields.size();
      for (size_t f = 0; sameFields && f < piece.fields.size(); ++f)
        sameFields = piece.fields[f].name == pieces[0].fields[f].name &&
                     piece.fields[f].centering == pieces[0].fields[f].centering;
      if (!sameFields)
        fail(positions[p], "this <Piece> has other data arrays than the first one");
      pointCount += piece.points.size();
      cellCount += piece.types.size();
      grid.polyhedra.polyhedra += piece.polyhedra.polyhedra;
      grid.polyhedra.tets += piece.polyhedra.tets;
      grid.polyhedra.pyramids += piece.polyhedra.pyramids;
      connectivityCount += piece.connectivity.size();
    }
    if (pointCount > NarrowPointIndex::kOutside)
      throw Error(path_, "", "more than 2^32 points are not supported"); // as buildMesh says
    grid.offsets = Buffer<int64_t>(cellCount + 1);
    grid.offsets[0] = 0;
    grid.connectivity = Buffer<uint32_t>(connectivityCount);
    grid.types = Buffer<uint8_t>(cellCount);
    for (const ScalarField &f : pieces[0].fields)
      grid.fields.push_back({f.name, f.centering, {}});
    uint64_t cellBase = 0, connectivityBase = 0;
    for (VtuGrid &piece : pieces) {
      const auto pointBase = uint32_t(grid.points.size());
      grid.points.insert(grid.points.end(), piece.points.begin(), piece.points.end());
      for (size_t i = 0; i < piece.types.size(); ++i) {
        grid.offsets[cellBase + i + 1] = piece.offsets[i + 1] + int64_t(connectivityBase);
        grid.types[cellBase + i] = piece.types[i];
      }
      for (size_t i = 0; i < piece.connectivity.size(); ++i)
        grid.connectivity[connectivityBase + i] = piece.connectivity[i] + pointBase;
      for (size_t f = 0; f < grid.fields.size(); ++f)
        grid.fields[f].values.insert(grid.fields[f].values.end(), piece.fields[f].values.begin(),
                                     piece.fields[f].values.end());
      cellBase += piece.types.size();
      connectivityBase += piece.connectivity.size();
      piece = {};
    }
    return grid;
  }

  std::string path_;
  MappedFile file_;
  std::string head_; ///< the XML that pugixml parses in place: all of it, or the part before appended data
  const char *xmlBase_ = "";
  pugi::xml_document doc_;
  const uint8_t *appended_ = nullptr; ///< first byte after the '_' marker
  bool appendedBase64_ = false;
  bool swap_ = false;
  int headerBytes_ = 4;
  bool compressed_ = false;
  mutable InflationBound inflation_{"", 0, 1};
};

} // namespace

UnstructuredGrid readVtu(const std::string &path) {
  VtuGrid grid = VtuReader(path).read();
  return {std::move(grid.points),
          {grid.offsets.begin(), grid.offsets.end()},
          {grid.connectivity.begin(), grid.connectivity.end()},
          {grid.types.begin(), grid.types.end()},
          std::move(grid.fields),
          grid.polyhedra};
}

Mesh loadVtu(const std::string &path) {
  VtuGrid grid = VtuReader(path).read();
  Mesh mesh =
      buildMesh(std::move(grid.points),
                CellBuffers{std::move(grid.offsets), std::move(grid.connectivity), std::move(grid.types)},
                std::move(grid.fields), path);
  mesh.polyhedra = grid.polyhedra;
  return mesh;
}

} // namespace uvr
