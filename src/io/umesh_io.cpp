// Wald's umesh binary format (umesh/UMesh.cpp, UMesh::writeTo and readFrom). Everything is little-endian:
//
//   uint64 magic               0x234235568 (current), 0x234235567 (no grids), 0x234235566 (one unnamed
//   scalar) vector<vec3f> vertices     each vector is a uint64 count followed by that many packed elements
//   uint64 per-vertex attribute count, then per attribute: int32 name length, name, vector<float> values
//                              (0x...566 has instead one vector<float> and no count)
//   uint64 per-element attribute count, always 0 (umesh defines no layout for them; absent in 0x...566)
//   vector<int32[3]> triangles, vector<int32[4]> quads
//   vector<int32[4]> tets, vector<int32[5]> pyramids, vector<int32[6]> wedges, vector<int32[8]> hexes
//   vector<Grid> grids (48 bytes each), vector<float> grid scalars   (0x...568 only)
//   vector<uint64> vertex tags (optional)
//
// Cells use VTK's corner order, which is uvr's Mesh layout, so each array is read straight into place.
#include "core/progress.h"
#include "io/file_buffer.h"
#include "io/mesh_io.h"
#include "io/output_file.h"
#include <uvr/error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>

namespace uvr {

static_assert(std::endian::native == std::endian::little, "umesh files are little-endian");
static_assert(sizeof(Vec3f) == 12);

namespace {

constexpr uint64_t kMagic = 0x234235568ull;
constexpr uint64_t kMagicWithoutGrids = 0x234235567ull;
constexpr uint64_t kMagicOneScalar = 0x234235566ull;
constexpr uint64_t kGridBytes = 48; // box4f domain, vec3i cell counts, int scalar offset

/// Each chunk of a long array is copied and checked on its own, so that progress can be shown.
constexpr uint64_t kChunkBytes = uint64_t(1) << 26;

class UmeshReader {
public:
  explicit UmeshReader(const std::string &path) : file_(path), progress_("reading " + path, file_.size()) {}

  Mesh read() {
    Mesh mesh;
    const uint64_t magic = value<uint64_t>("the magic number");
    if (magic != kMagic && magic != kMagicWithoutGrids && magic != kMagicOneScalar)
      fail(0, "not a umesh file: magic number 0x" + hex(magic) + ", expected 0x" + hex(kMagic));

    array(mesh.points, 1, "vertices");
    const uint64_t pointCount = mesh.points.size();
    checkPointsFinite(mesh.points);

    if (magic == kMagicOneScalar) {
      addField(mesh, "scalars", pointCount);
    } else {
      const uint64_t attributes = value<uint64_t>("the per-vertex attribute count");
      if (attributes > remaining() / 12) // a name length and a value count each, at least
        fail(position_ - 8, std::to_string(attributes) + " per-vertex attributes declared, but only " +
                                std::to_string(remaining()) + " bytes follow");
      for (uint64_t a = 0; a < attributes; ++a) {
        const uint64_t at = position_;
        const int32_t length = value<int32_t>("an attribute name length");
        if (length < 0 || uint64_t(length) > remaining())
          fail(at, "attribute " + std::to_string(a) + " has a name of " + std::to_string(length) +
                       " bytes, but only " + std::to_string(remaining()) + " bytes follow");
        std::string name(size_t(length), '\0');
        bytes(name.data(), uint64_t(length));
        addField(mesh, name.empty() ? "scalars" : name, pointCount);
      }
      const uint64_t at = position_;
      const uint64_t perElement = value<uint64_t>("the per-element attribute count");
      if (perElement != 0)
        fail(at, std::to_string(perElement) +
                     " per-element attributes declared; the umesh format defines no layout for them");
    }

    mesh.skippedCells += skip(12, "triangles") + skip(16, "quads");
    readCells(mesh.tets, 4, CellType::Tetra, "tets", mesh);
    readCells(mesh.pyramids, 5, CellType::Pyramid, "pyramids", mesh);
    readCells(mesh.wedges, 6, CellType::Wedge, "wedges", mesh);
    readCells(mesh.hexes, 8, CellType::Hexahedron, "hexes", mesh);
    if (magic == kMagic) {
      const uint64_t at = position_;
      if (const uint64_t grids = skip(kGridBytes, "grids"); grids > 0)
        fail(at, std::to_string(grids) + " structured grids (umesh's embedded voxel bricks): not supported");
      skip(4, "grid scalars");
    }
    if (remaining() > 0)
      skip(8, "vertex tags");
    if (remaining() > 0)
      fail(position_, std::to_string(remaining()) + " bytes after the last array");
    progress_.finish();

    // The cell and point order every other format gets from buildMesh. uvr writes .umesh files in that order
    // (points numbered by first use), and then the costly reordering is skipped.
    if (!firstUseOrder_)
      orderSpatially(mesh);
    return mesh;
  }

private:
  [[noreturn]] void fail(uint64_t at, const std::string &what) const {
    throw Error(file_.path(), "byte " + std::to_string(at), what);
  }

  static std::string hex(uint64_t v) {
    char text[20];
    std::snprintf(text, sizeof text, "%llx", static_cast<unsigned long long>(v));
    return text;
  }

  uint64_t remaining() const { return file_.size() - position_; }

  void bytes(void *dst, uint64_t n) {
    for (uint64_t done = 0; done < n;) {
      const uint64_t chunk = std::min(kChunkBytes, n - done);
      file_.read(position_ + done, static_cast<uint8_t *>(dst) + done, chunk);
      done += chunk;
      progress_.advance(chunk);
    }
    position_ += n;
  }

  template <typename T> T value(const char *what) {
    if (remaining() < sizeof(T))
      fail(position_, std::string("the file ends before ") + what);
    T v;
    bytes(&v, sizeof(T));
    return v;
  }

  /// Reads an array's count and checks that its elements of `elementBytes` fit in the rest of the file.
  uint64_t count(uint64_t elementBytes, const std::string &what) {
    const uint64_t at = position_;
    const uint64_t n = value<uint64_t>(("the count of " + what).c_str());
    if (n > remaining() / elementBytes)
      fail(at, what + ": " + std::to_string(n) + " entries of " + std::to_string(elementBytes) +
                   " bytes declared, but only " + std::to_string(remaining()) + " bytes follow");
    return n;
  }

  /// Reads a vector of `n` elements of `components` values of T.
  template <typename T>
  uint64_t array(UninitVector<T> &values, uint64_t components, const std::string &what) {
    const uint64_t n = count(components * sizeof(T), what);
    values.resize(n * components);
    bytes(values.data(), n * components * sizeof(T));
    return n;
  }

  uint64_t skip(uint64_t elementBytes, const std::string &what) {
    const uint64_t n = count(elementBytes, what);
    position_ += n * elementBytes;
    progress_.advance(n * elementBytes);
    return n;
  }

  void addField(Mesh &mesh, const std::string &name, uint64_t pointCount) {
    const uint64_t at = position_;
    ScalarField field{name, Centering::Point, {}};
    const uint64_t n = array(field.values, 1, "values of attribute '" + name + "'");
    if (n == 0 && pointCount > 0) // umesh keeps empty attributes around; they hold no field
      return;
    if (n != pointCount)
      fail(at, "attribute '" + name + "' has " + std::to_string(n) + " values for " +
                   std::to_string(pointCount) + " vertices");
    mesh.fields.push_back(std::move(field));
  }

  void checkPointsFinite(std::span<const Vec3f> points) const {
    const uint64_t n = points.size();
    const uint64_t bad = tbb::parallel_reduce(
        tbb::blocked_range<uint64_t>(0, n, 1 << 16), n,
        [&](const tbb::blocked_range<uint64_t> &r, uint64_t found) {
          for (uint64_t i = r.begin(); i < r.end() && i < found; ++i)
            if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y) || !std::isfinite(points[i].z))
              return i;
          return found;
        },
        [](uint64_t a, uint64_t b) { return std::min(a, b); });
    if (bad < n)
      fail(8 + 8 + bad * 12, "vertex " + std::to_string(bad) + " is not finite");
  }

  /// Reads one cell type's array and, in one parallel pass over chunks of cells, each read from the file by
  /// the thread that then: checks its point indices (signed in the file), winds each cell as VTK expects, and
  /// learns whether the points are numbered by first use (each corner is a point seen before or the next
  /// unseen one). Reading inside the pass spreads the copy from the page cache over the cores too.
  void readCells(UninitVector<uint32_t> &cells, int corners, CellType type, const std::string &what,
                 Mesh &mesh) {
    const uint64_t cellBytes = uint64_t(corners) * sizeof(uint32_t);
    const uint64_t n = count(cellBytes, what);
    const uint64_t first = position_;
    cells.resize(n * uint64_t(corners));
    position_ += n * cellBytes;
    const uint32_t pointCount = uint32_t(std::min<uint64_t>(mesh.points.size(), UINT32_MAX));
    constexpr uint64_t kChunkCells = 1 << 14;
    struct Chunk {
      uint64_t firstBad = UINT64_MAX;
      uint64_t inverted = 0;
      int64_t largest = -1; ///< the largest index in the chunk
      int64_t needs = -1;   ///< the largest index that is more than one past all before it in the chunk
    };
    std::vector<Chunk> chunks((n + kChunkCells - 1) / kChunkCells);
    tbb::parallel_for(uint64_t(0), uint64_t(chunks.size()), [&](uint64_t k) {
      Chunk &chunk = chunks[k];
      const uint64_t begin = k * kChunkCells, end = std::min(n, begin + kChunkCells);
      file_.read(first + begin * cellBytes, &cells[begin * uint64_t(corners)], (end - begin) * cellBytes);
      progress_.advance((end - begin) * cellBytes);
      for (uint64_t c = begin; c < end; ++c) {
        uint32_t *v = &cells[c * uint64_t(corners)];
        bool valid = true;
        for (int i = 0; i < corners; ++i) {
          valid &= v[i] < pointCount; // a negative int32 reads as a large uint32
          if (int64_t(v[i]) > chunk.largest + 1)
            chunk.needs = std::max(chunk.needs, int64_t(v[i]));
          chunk.largest = std::max(chunk.largest, int64_t(v[i]));
        }
        if (!valid) {
          chunk.firstBad = c;
          return;
        }
        chunk.inverted += orientCell(type, v, mesh.points);
      }
    });
    for (const Chunk &chunk : chunks) {
      if (chunk.firstBad != UINT64_MAX) {
        const uint32_t *v = &cells[chunk.firstBad * uint64_t(corners)];
        const int corner = int(std::find_if(v, v + corners, [&](uint32_t i) { return i >= pointCount; }) - v);
        fail(first + (chunk.firstBad * uint64_t(corners) + uint64_t(corner)) * 4,
             what + ": cell " + std::to_string(chunk.firstBad) + " names vertex " +
                 std::to_string(int32_t(v[corner])) + ", outside [0, " + std::to_string(mesh.points.size()) +
                 ")");
      }
      // Within the chunk, a corner more than one past the chunk's earlier ones must be at most one past
      // those of all earlier chunks. (Winding swaps corners within a cell, after they were looked at.)
      firstUseOrder_ &= chunk.needs <= largestSoFar_ + 1;
      largestSoFar_ = std::max(largestSoFar_, chunk.largest);
      mesh.invertedCells += chunk.inverted;
    }
  }

  InputFile file_;
  Progress progress_;
  uint64_t position_ = 0;
  bool firstUseOrder_ = true;
  int64_t largestSoFar_ = -1; ///< the largest point index in the cells read so far
};

} // namespace

Mesh readUmesh(const std::string &path) { return UmeshReader(path).read(); }

void writeUmesh(const std::string &path, const Mesh &mesh) {
  for (const ScalarField &field : mesh.fields)
    if (field.centering != Centering::Point)
      throw Error(path, "",
                  "umesh stores per-vertex scalars only, and '" + field.name +
                      "' is a cell field: keep point fields only, or write .vtu");
  if (mesh.points.size() > uint64_t(INT32_MAX))
    throw Error(path, "", "umesh indexes vertices with 32-bit signed integers: too many points");

  uint64_t total = 8 + 8 + mesh.points.size() * 12 + 8 + 8 * 10; // magic, vertices, counts
  for (const ScalarField &field : mesh.fields)
    total += 4 + field.name.size() + 8 + field.values.size() * 4;
  total += 4 * (mesh.tets.size() + mesh.pyramids.size() + mesh.wedges.size() + mesh.hexes.size());
  Progress progress("writing " + path, total);

  OutputFile out(path);
  auto vector = [&](const void *data, uint64_t count, uint64_t elementBytes) {
    out.writeValue(count);
    const auto *bytes = static_cast<const uint8_t *>(data);
    for (uint64_t done = 0, size = count * elementBytes; done < size;) {
      const uint64_t chunk = std::min(kChunkBytes, size - done);
      out.write(bytes + done, chunk);
      done += chunk;
      progress.advance(chunk);
    }
  };
  out.writeValue(kMagic);
  vector(mesh.points.data(), mesh.points.size(), 12);
  out.writeValue(uint64_t(mesh.fields.size()));
  for (const ScalarField &field : mesh.fields) {
    out.writeValue(int32_t(field.name.size()));
    out.write(field.name.data(), field.name.size());
    vector(field.values.data(), field.values.size(), 4);
  }
  out.writeValue(uint64_t(0)); // per-element attributes
  vector(nullptr, 0, 12);      // triangles
  vector(nullptr, 0, 16);      // quads
  vector(mesh.tets.data(), mesh.tetCount(), 16);
  vector(mesh.pyramids.data(), mesh.pyramidCount(), 20);
  vector(mesh.wedges.data(), mesh.wedgeCount(), 24);
  vector(mesh.hexes.data(), mesh.hexCount(), 32);
  vector(nullptr, 0, kGridBytes); // grids
  vector(nullptr, 0, 4);          // grid scalars
  vector(nullptr, 0, 8);          // vertex tags
  out.close();
}

} // namespace uvr
