// VTK XML unstructured grid writer: one Piece, all arrays appended raw after the XML, UInt64 headers.
//
// Arrays are produced block by block from the Mesh (connectivity widened to Int64, offsets and type codes
// computed), so no whole-array copy is made; with zlib the blocks are compressed in parallel, as VTK's
// vtkZLibDataCompressor lays them out: [block count, block size, last block size, compressed sizes...].
#include "core/progress.h"
#include "io/mesh_io.h"
#include "io/output_file.h"
#include <uvr/error.h>

#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdio>
#include <cstring>
#include <functional>
#include <vector>

namespace uvr {

static_assert(std::endian::native == std::endian::little, "the writer declares LittleEndian");

namespace {

/// A multiple of every value size written (1, 4, 8, 12), so no value straddles two blocks.
constexpr uint64_t kBlockBytes = uint64_t(3) << 18;

/// One DataArray: its XML attributes, and a function that writes any block of its bytes.
struct ArraySource {
  std::string xmlAttributes;
  uint64_t bytes = 0;
  std::function<void(uint64_t firstByte, uint64_t count, uint8_t *dst)> fill;
};

ArraySource copyOf(std::string xmlAttributes, const void *data, uint64_t bytes) {
  const auto *source = static_cast<const uint8_t *>(data);
  return {std::move(xmlAttributes), bytes, [source](uint64_t first, uint64_t count, uint8_t *dst) {
            std::memcpy(dst, source + first, count);
          }};
}

/// `text` for an XML attribute; throws uvr::Error naming `path` for a control character that XML 1.0 cannot
/// hold at all (NUL, and the others but tab, line feed and carriage return, kept as references).
std::string escapeXml(const std::string &text, const std::string &path) {
  std::string out;
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 && c != '\t' && c != '\n' && c != '\r') {
      std::string shown;
      for (char d : text.substr(0, 80)) {
        const auto b = static_cast<unsigned char>(d);
        char hex[8];
        std::snprintf(hex, sizeof hex, "\\x%02x", b);
        shown += b < 0x20 ? std::string(hex) : std::string(1, d);
      }
      throw Error(path, "",
                  "field name '" + shown + "' holds control character " + std::to_string(int(byte)) +
                      ", which a .vtu file cannot hold");
    }
    if (byte < 0x20) { // tab, line feed, carriage return: a parser would read them back as spaces
      out += "&#" + std::to_string(int(byte)) + ";";
      continue;
    }
    switch (c) {
    case '&':
      out += "&amp;";
      break;
    case '<':
      out += "&lt;";
      break;
    case '>':
      out += "&gt;";
      break;
    case '"':
      out += "&quot;";
      break;
    default:
      out += c;
    }
  }
  return out;
}

/// The four cell arrays of a Mesh, seen as one: cell c's type, corner count and first connectivity entry.
class CellSequence {
public:
  explicit CellSequence(const Mesh &mesh) {
    const std::array<const UninitVector<uint32_t> *, 4> arrays = {&mesh.tets, &mesh.pyramids, &mesh.wedges,
                                                                  &mesh.hexes};
    uint64_t cells = 0, entries = 0;
    for (int t = 0; t < 4; ++t) {
      parts_[t] = {arrays[t]->data(), cells, entries, kCorners[t], kTypes[t]};
      cells += arrays[t]->size() / uint64_t(kCorners[t]);
      entries += arrays[t]->size();
    }
    parts_[4] = {nullptr, cells, entries, 1, 0};
  }
  uint64_t cellCount() const { return parts_[4].firstCell; }
  uint64_t entryCount() const { return parts_[4].firstEntry; }

  /// Writes Int64 point indices for connectivity entries [first, first + count).
  void connectivity(uint64_t first, uint64_t count, int64_t *dst) const {
    for (int t = 0; t < 4 && count > 0; ++t) {
      const Part &p = parts_[t];
      const uint64_t end = parts_[t + 1].firstEntry;
      for (; first < end && count > 0; ++first, --count)
        *dst++ = int64_t(p.indices[first - p.firstEntry]);
    }
  }
  /// Writes each cell's end offset for cells [first, first + count).
  void offsets(uint64_t first, uint64_t count, int64_t *dst) const {
    for (int t = 0; t < 4 && count > 0; ++t) {
      const Part &p = parts_[t];
      for (; first < parts_[t + 1].firstCell && count > 0; ++first, --count)
        *dst++ = int64_t(p.firstEntry + (first - p.firstCell + 1) * uint64_t(p.corners));
    }
  }
  void types(uint64_t first, uint64_t count, uint8_t *dst) const {
    for (int t = 0; t < 4 && count > 0; ++t)
      for (; first < parts_[t + 1].firstCell && count > 0; ++first, --count)
        *dst++ = parts_[t].type;
  }

private:
  static constexpr std::array<int, 4> kCorners = {4, 5, 6, 8};
  static constexpr std::array<uint8_t, 4> kTypes = {uint8_t(CellType::Tetra), uint8_t(CellType::Pyramid),
                                                    uint8_t(CellType::Wedge), uint8_t(CellType::Hexahedron)};
  struct Part {
    const uint32_t *indices;
    uint64_t firstCell, firstEntry;
    int corners;
    uint8_t type;
  };
  std::array<Part, 5> parts_;
};

/// An array's bytes as they go to the file: the UInt64 header words, then the (compressed) blocks.
struct EncodedArray {
  std::vector<uint64_t> header;
  std::vector<std::vector<uint8_t>> blocks; ///< compressed; empty when the array is written raw
  uint64_t size() const {
    uint64_t total = header.size() * 8;
    for (const auto &block : blocks)
      total += block.size();
    return total;
  }
};

EncodedArray compressArray(const ArraySource &source, const std::string &path) {
  const uint64_t blockCount = (source.bytes + kBlockBytes - 1) / kBlockBytes;
  EncodedArray encoded;
  encoded.blocks.resize(blockCount);
  tbb::parallel_for(uint64_t(0), blockCount, [&](uint64_t b) {
    const uint64_t first = b * kBlockBytes, count = std::min(kBlockBytes, source.bytes - first);
    std::vector<uint8_t> raw(count);
    source.fill(first, count, raw.data());
    uLongf compressedSize = compressBound(uLong(count));
    std::vector<uint8_t> &compressed = encoded.blocks[b];
    compressed.resize(compressedSize);
    // Level 1: the fastest; the higher levels shrink these arrays only a little more.
    if (compress2(compressed.data(), &compressedSize, raw.data(), uLong(count), 1) != Z_OK)
      throw Error(path, "", "zlib compression failed");
    compressed.resize(compressedSize);
  });
  const uint64_t last = source.bytes - (blockCount ? (blockCount - 1) * kBlockBytes : 0);
  encoded.header = {blockCount, kBlockBytes, blockCount ? last : 0};
  for (const auto &block : encoded.blocks)
    encoded.header.push_back(block.size());
  return encoded;
}

} // namespace

void writeVtu(const std::string &path, const Mesh &mesh, bool compress) {
  const CellSequence cells(mesh);
  std::vector<ArraySource> pointData, cellData;
  for (const ScalarField &field : mesh.fields) {
    const uint64_t expected = field.centering == Centering::Point ? mesh.points.size() : cells.cellCount();
    if (field.values.size() != expected)
      throw Error(path, "",
                  "field '" + field.name + "' has " + std::to_string(field.values.size()) +
                      " values, expected " + std::to_string(expected));
    (field.centering == Centering::Point ? pointData : cellData)
        .push_back(copyOf("type=\"Float32\" Name=\"" + escapeXml(field.name, path) + "\"",
                          field.values.data(), field.values.size() * 4));
  }
  const ArraySource points = copyOf("type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\"",
                                    mesh.points.data(), mesh.points.size() * 12);
  const ArraySource connectivity = {"type=\"Int64\" Name=\"connectivity\"", cells.entryCount() * 8,
                                    [&](uint64_t first, uint64_t count, uint8_t *dst) {
                                      cells.connectivity(first / 8, count / 8,
                                                         reinterpret_cast<int64_t *>(dst));
                                    }};
  const ArraySource offsets = {"type=\"Int64\" Name=\"offsets\"", cells.cellCount() * 8,
                               [&](uint64_t first, uint64_t count, uint8_t *dst) {
                                 cells.offsets(first / 8, count / 8, reinterpret_cast<int64_t *>(dst));
                               }};
  const ArraySource types = {
      "type=\"UInt8\" Name=\"types\"", cells.cellCount(),
      [&](uint64_t first, uint64_t count, uint8_t *dst) { cells.types(first, count, dst); }};

  // The XML names each array's offset into the appended data, so every array's encoded size comes first.
  std::vector<const ArraySource *> order;
  for (const ArraySource &a : pointData)
    order.push_back(&a);
  for (const ArraySource &a : cellData)
    order.push_back(&a);
  for (const ArraySource *a : {&points, &connectivity, &offsets, &types})
    order.push_back(a);

  uint64_t totalBytes = 0;
  for (const ArraySource *a : order)
    totalBytes += a->bytes;
  Progress progress((compress ? "compressing and writing " : "writing ") + path, totalBytes);

  std::vector<EncodedArray> encoded(order.size());
  std::vector<uint64_t> appendedOffsets;
  uint64_t offset = 0;
  for (size_t i = 0; i < order.size(); ++i) {
    if (compress) {
      encoded[i] = compressArray(*order[i], path);
      progress.advance(order[i]->bytes / 2);
    } else {
      encoded[i].header = {order[i]->bytes};
    }
    appendedOffsets.push_back(offset);
    offset += compress ? encoded[i].size() : 8 + order[i]->bytes;
  }

  auto element = [&](size_t i) {
    return "        <DataArray " + order[i]->xmlAttributes + " format=\"appended\" offset=\"" +
           std::to_string(appendedOffsets[i]) + "\"/>\n";
  };
  std::string xml = "<?xml version=\"1.0\"?>\n"
                    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
                    "header_type=\"UInt64\"";
  if (compress)
    xml += " compressor=\"vtkZLibDataCompressor\"";
  xml += ">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"" + std::to_string(mesh.points.size()) +
         "\" NumberOfCells=\"" + std::to_string(cells.cellCount()) + "\">\n      <PointData>\n";
  size_t next = 0;
  for (; next < pointData.size(); ++next)
    xml += element(next);
  xml += "      </PointData>\n      <CellData>\n";
  for (; next < pointData.size() + cellData.size(); ++next)
    xml += element(next);
  xml += "      </CellData>\n      <Points>\n" + element(next++) + "      </Points>\n      <Cells>\n";
  for (; next < order.size(); ++next)
    xml += element(next);
  xml += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";

  OutputFile out(path);
  out.write(xml.data(), xml.size());
  std::vector<uint8_t> block(kBlockBytes);
  for (size_t i = 0; i < order.size(); ++i) {
    out.write(encoded[i].header.data(), encoded[i].header.size() * 8);
    if (compress) {
      for (const auto &compressed : encoded[i].blocks)
        out.write(compressed.data(), compressed.size());
      progress.advance(order[i]->bytes - order[i]->bytes / 2);
      continue;
    }
    for (uint64_t first = 0; first < order[i]->bytes; first += kBlockBytes) {
      const uint64_t count = std::min(kBlockBytes, order[i]->bytes - first);
      order[i]->fill(first, count, block.data());
      out.write(block.data(), count);
      progress.advance(count);
    }
  }
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  out.write(tail.data(), tail.size());
  out.close();
}

} // namespace uvr
