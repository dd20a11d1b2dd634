// The .umesh reader and writer, the .vtu writer, the Gmsh reader and time-step series: round trips, files
// laid out by hand from the formats' specifications, and malformed input.
#include "io/mesh_io.h"
#include "mesh/mesh_stats.h"
#include "mesh/mesh_view.h"
#include "mesh/procedural_mesh.h"
#include <uvr/error.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>

using namespace uvr;

namespace {

namespace fs = std::filesystem;

/// A fresh directory per test, removed afterwards.
class Formats : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("uvr_formats_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string &name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

/// Every cell type, each a jittered lattice of its own, with point field "f" and cell field "f_cell".
Mesh mixedMesh() {
  UnstructuredGrid all;
  all.offsets.assign(1, 0);
  all.fields = {{"f", Centering::Point, {}}, {"f_cell", Centering::Cell, {}}};
  float x = 0.f;
  for (CellType type : {CellType::Hexahedron, CellType::Tetra, CellType::Wedge, CellType::Pyramid}) {
    UnstructuredGrid grid = makeBoxGrid(
        type, 3, Box3f{{x, 0.f, 0.f}, {x + 1.f, 1.f, 1.f}}, [](Vec3f p) { return p.x + 2.f * p.y - p.z; },
        0.2f, unsigned(type));
    const auto base = int64_t(all.points.size());
    all.points.insert(all.points.end(), grid.points.begin(), grid.points.end());
    for (size_t c = 1; c < grid.offsets.size(); ++c)
      all.offsets.push_back(grid.offsets[c] + int64_t(all.connectivity.size()));
    for (int64_t id : grid.connectivity)
      all.connectivity.push_back(id + base);
    all.types.insert(all.types.end(), grid.types.begin(), grid.types.end());
    for (ScalarField &into : all.fields)
      for (const ScalarField &field : grid.fields)
        if (field.name == into.name)
          into.values.insert(into.values.end(), field.values.begin(), field.values.end());
    x += 1.5f;
  }
  return buildMesh(std::move(all), "mixed");
}

bool samePoints(std::span<const Vec3f> a, std::span<const Vec3f> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3f)) == 0;
}

void expectSameMesh(const Mesh &a, const Mesh &b) {
  EXPECT_TRUE(samePoints(a.points, b.points));
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.pyramids, b.pyramids);
  EXPECT_EQ(a.wedges, b.wedges);
  EXPECT_EQ(a.hexes, b.hexes);
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (size_t f = 0; f < a.fields.size(); ++f) {
    EXPECT_EQ(a.fields[f].name, b.fields[f].name);
    EXPECT_EQ(a.fields[f].centering, b.fields[f].centering);
    EXPECT_EQ(a.fields[f].values, b.fields[f].values) << a.fields[f].name;
  }
}

Mesh withoutCellFields(Mesh mesh) {
  std::erase_if(mesh.fields, [](const ScalarField &f) { return f.centering == Centering::Cell; });
  return mesh;
}

std::string fileBytes(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void writeBytes(const std::string &path, const std::string &bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// Little-endian bytes of a value, as umesh writes them.
template <typename T> std::string le(T value) { return {reinterpret_cast<const char *>(&value), sizeof(T)}; }
/// A umesh vector: its element count, then the elements, each of `per` values.
template <typename T> std::string leVector(const std::vector<T> &values, size_t per = 1) {
  return le(uint64_t(values.size() / per)) +
         std::string(reinterpret_cast<const char *>(values.data()), values.size() * sizeof(T));
}

/// The error text of `f`, or "" when it throws none.
template <typename F> std::string errorOf(F &&f) {
  try {
    f();
  } catch (const Error &e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST_F(Formats, UmeshRoundTripIsExact) {
  const Mesh mesh = withoutCellFields(mixedMesh());
  ASSERT_GT(mesh.tetCount() * mesh.pyramidCount() * mesh.wedgeCount() * mesh.hexCount(), 0u);
  writeUmesh(path("m.umesh"), mesh);
  const Mesh back = loadMesh(path("m.umesh"));
  expectSameMesh(mesh, back);
  EXPECT_EQ(back.invertedCells, 0u);
  EXPECT_EQ(back.skippedCells, 0u);
}

TEST_F(Formats, UmeshRefusesCellFields) {
  const std::string error = errorOf([&] { writeUmesh(path("m.umesh"), mixedMesh()); });
  EXPECT_NE(error.find("'f_cell' is a cell field"), std::string::npos) << error;
  EXPECT_NE(error.find("point fields"), std::string::npos) << error; // `uvr convert` names --field
}

// A file laid out by hand from umesh's UMesh::writeTo: one tet wound the wrong way, one triangle, one named
// attribute, and a vertex-tag array at the end.
TEST_F(Formats, UmeshByTheSpecification) {
  const std::vector<float> vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<float> temperature = {10, 11, 12, 13};
  const std::string name = "temperature";
  const std::string file = le(uint64_t(0x234235568)) + le(uint64_t(4)) +
                           std::string(reinterpret_cast<const char *>(vertices.data()), 48) +
                           le(uint64_t(1)) + le(int32_t(name.size())) + name + leVector(temperature) +
                           le(uint64_t(0)) + leVector(std::vector<int32_t>{0, 1, 2}, 3) +
                           leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{0, 2, 1, 3}, 4) +
                           leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{}) +
                           leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{}) +
                           leVector(std::vector<float>{}) + leVector(std::vector<uint64_t>{7, 7, 7, 7});
  writeBytes(path("hand.umesh"), file);
  const Mesh mesh = readUmesh(path("hand.umesh"));
  EXPECT_EQ(mesh.points.size(), 4u);
  EXPECT_EQ(mesh.tetCount(), 1u);
  EXPECT_EQ(mesh.cellCount(), 1u);
  EXPECT_EQ(mesh.skippedCells, 1u);
  EXPECT_EQ(mesh.invertedCells, 1u);
  ASSERT_EQ(mesh.fields.size(), 1u);
  EXPECT_EQ(mesh.fields[0].name, "temperature");
  // Points are renumbered by first use; each keeps its value.
  for (int i = 0; i < 4; ++i) {
    const Vec3f p = mesh.points[size_t(i)];
    EXPECT_EQ(mesh.fields[0].values[size_t(i)], 10.f + (p.x > 0 ? 1.f : p.y > 0 ? 2.f : p.z > 0 ? 3.f : 0.f));
  }

  // The oldest layout: one unnamed scalar array, no attribute counts, no grids.
  const std::string old = le(uint64_t(0x234235566)) + le(uint64_t(4)) +
                          std::string(reinterpret_cast<const char *>(vertices.data()), 48) +
                          leVector(temperature) + leVector(std::vector<int32_t>{}) +
                          leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{0, 1, 2, 3}, 4) +
                          leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{}) +
                          leVector(std::vector<int32_t>{});
  writeBytes(path("old.umesh"), old);
  const Mesh oldMesh = readUmesh(path("old.umesh"));
  EXPECT_EQ(oldMesh.tetCount(), 1u);
  EXPECT_EQ(oldMesh.invertedCells, 0u);
  ASSERT_EQ(oldMesh.fields.size(), 1u);
  EXPECT_EQ(oldMesh.fields[0].name, "scalars");
}

TEST_F(Formats, UmeshTruncatedAtEveryByte) {
  Mesh mesh = withoutCellFields(mixedMesh());
  writeUmesh(path("m.umesh"), mesh);
  const std::string bytes = fileBytes(path("m.umesh"));
  // Every cut through the header and the vertex count, then a stride of cuts through the rest.
  for (size_t cut = 0; cut < bytes.size(); cut += cut < 120 ? 1 : 211) {
    writeBytes(path("cut.umesh"), bytes.substr(0, cut));
    const std::string error = errorOf([&] { readUmesh(path("cut.umesh")); });
    EXPECT_NE(error.find(path("cut.umesh") + ", byte "), std::string::npos)
        << "cut at " << cut << ": " << error;
  }
  writeBytes(path("long.umesh"), bytes + "x");
  EXPECT_NE(errorOf([&] { readUmesh(path("long.umesh")); }).find("1 bytes after the last array"),
            std::string::npos);
}

TEST_F(Formats, UmeshOversizedCountsAndBadIndices) {
  const std::vector<float> vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  auto file = [&](uint64_t tetCount, int32_t lastIndex) {
    return le(uint64_t(0x234235568)) + le(uint64_t(4)) +
           std::string(reinterpret_cast<const char *>(vertices.data()), 48) + le(uint64_t(0)) +
           le(uint64_t(0)) + leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{}) +
           le(tetCount) + leVector(std::vector<int32_t>{0, 1, 2, lastIndex}).substr(8) +
           leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{}) +
           leVector(std::vector<int32_t>{}) + leVector(std::vector<int32_t>{}) +
           leVector(std::vector<float>{});
  };
  const uint64_t tetCountAt = 8 + 8 + 48 + 8 + 8 + 8 + 8;
  writeBytes(path("huge.umesh"), file(uint64_t(1) << 61, 3));
  std::string error = errorOf([&] { readUmesh(path("huge.umesh")); });
  EXPECT_NE(error.find(path("huge.umesh") + ", byte " + std::to_string(tetCountAt) +
                       ": tets: " + std::to_string(uint64_t(1) << 61) + " entries of 16 bytes declared"),
            std::string::npos)
      << error;

  writeBytes(path("negative.umesh"), file(1, -1));
  error = errorOf([&] { readUmesh(path("negative.umesh")); });
  EXPECT_NE(error.find("byte " + std::to_string(tetCountAt + 8 + 12) +
                       ": tets: cell 0 names vertex -1, outside [0, 4)"),
            std::string::npos)
      << error;

  writeBytes(path("magic.umesh"), "not a umesh file at all");
  EXPECT_NE(errorOf([&] { readUmesh(path("magic.umesh")); }).find(", byte 0: not a umesh file"),
            std::string::npos);
}

TEST_F(Formats, VtuWriteReadRoundTripIsExact) {
  const Mesh mesh = mixedMesh();
  for (bool compress : {false, true}) {
    writeVtu(path("m.vtu"), mesh, compress);
    const Mesh back = loadMesh(path("m.vtu"));
    expectSameMesh(mesh, back);
    EXPECT_EQ(back.invertedCells, 0u);
  }
}

TEST_F(Formats, SaveMeshByExtension) {
  const Mesh mesh = withoutCellFields(mixedMesh());
  saveMesh(path("a.VTU"), mesh);
  saveMesh(path("a.umesh"), mesh);
  expectSameMesh(loadMesh(path("a.VTU")), loadMesh(path("a.umesh")));
  const std::string error = errorOf([&] { saveMesh(path("a.obj"), mesh); });
  EXPECT_NE(error.find("cannot write mesh format '.obj'"), std::string::npos) << error;
}

namespace {

/// A jittered box grid of one cell type as files list cells: shuffled, and every third one wound the other
/// way.
UnstructuredGrid shuffledGrid(CellType type) {
  const UnstructuredGrid lattice = makeBoxGrid(
      type, 4, Box3f{{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}}, [](Vec3f p) { return p.x - p.z; }, 0.2f, 5);
  const size_t corners = size_t(vertexCount(uint8_t(type))), cellCount = lattice.types.size();
  std::vector<size_t> order(cellCount);
  std::iota(order.begin(), order.end(), size_t(0));
  std::shuffle(order.begin(), order.end(), std::mt19937(9));
  UnstructuredGrid grid = lattice;
  grid.connectivity.clear();
  for (size_t i = 0; i < cellCount; ++i) {
    std::vector<int64_t> v(lattice.connectivity.begin() + std::ptrdiff_t(order[i] * corners),
                           lattice.connectivity.begin() + std::ptrdiff_t((order[i] + 1) * corners));
    if (i % 3 == 0) { // mirrored: a tet's or pyramid's base reversed, a wedge's or hexahedron's ends swapped
      if (type == CellType::Tetra)
        std::swap(v[1], v[2]);
      else if (type == CellType::Pyramid)
        std::swap(v[1], v[3]);
      else
        std::rotate(v.begin(), v.begin() + std::ptrdiff_t(corners / 2), v.end());
    }
    grid.connectivity.insert(grid.connectivity.end(), v.begin(), v.end());
  }
  for (size_t f = 0; f < grid.fields.size(); ++f)
    if (grid.fields[f].centering == Centering::Cell)
      for (size_t i = 0; i < cellCount; ++i)
        grid.fields[f].values[i] = lattice.fields[f].values[order[i]];
  return grid;
}

/// The mesh that buildMesh makes of the grid's cells handed over, point indices narrowed.
Mesh buildHandedOver(const UnstructuredGrid &grid) {
  CellBuffers cells{Buffer<int64_t>(grid.offsets.size()), Buffer<uint32_t>(grid.connectivity.size()),
                    Buffer<uint8_t>(grid.types.size())};
  std::copy(grid.offsets.begin(), grid.offsets.end(), cells.offsets.begin());
  std::transform(grid.connectivity.begin(), grid.connectivity.end(), cells.connectivity.begin(),
                 [](int64_t id) { return uint32_t(id); });
  std::copy(grid.types.begin(), grid.types.end(), cells.types.begin());
  return buildMesh(UninitVector<Vec3f>(grid.points), std::move(cells), std::vector<ScalarField>(grid.fields),
                   "handed.vtu");
}

} // namespace

// Cells of one type back to back become the mesh's cell array in place; any others are grouped by type. Both
// give the mesh that the grouping of a grid viewed in place gives.
TEST(BuildMesh, HandedOverCellsBuildAsViewedOnes) {
  for (CellType type : {CellType::Tetra, CellType::Pyramid, CellType::Wedge, CellType::Hexahedron}) {
    UnstructuredGrid grid = shuffledGrid(type);
    const Mesh viewed = buildMesh(UnstructuredGrid(grid), "viewed.vtu");
    EXPECT_GT(viewed.invertedCells, 0u);
    const Mesh handed = buildHandedOver(grid);
    expectSameMesh(viewed, handed);
    EXPECT_EQ(handed.invertedCells, viewed.invertedCells);

    // A triangle after them, skipped: the cells are no longer all of one type.
    grid.types.push_back(5);
    grid.connectivity.insert(grid.connectivity.end(), {0, 1, 2});
    grid.offsets.push_back(grid.offsets.back() + 3);
    for (ScalarField &field : grid.fields)
      if (field.centering == Centering::Cell)
        field.values.push_back(0.f);
    const Mesh mixed = buildHandedOver(grid);
    EXPECT_EQ(mixed.skippedCells, 1u);
    expectSameMesh(viewed, mixed);
  }
  UnstructuredGrid grid = shuffledGrid(CellType::Tetra);
  grid.connectivity[41] = int64_t(grid.points.size());
  const std::string error = errorOf([&] { buildHandedOver(grid); });
  EXPECT_NE(error.find("cell 10: point index " + std::to_string(grid.points.size()) + " outside"),
            std::string::npos)
      << error;

  // The first bad cell is named, by its first bad index, before a field of the wrong size: as the grouping
  // of a grid viewed in place says.
  grid.connectivity[4 * 25 + 1] = int64_t(grid.points.size()) + 3;
  grid.connectivity[4 * 25 + 2] = int64_t(grid.points.size()) + 5;
  grid.connectivity[4 * 30] = int64_t(grid.points.size()) + 7;
  grid.fields[0].values.pop_back();
  const std::string viewedError = errorOf([&] { buildMesh(UnstructuredGrid(grid), "handed.vtu"); });
  EXPECT_NE(viewedError.find("cell 10: point index"), std::string::npos) << viewedError;
  EXPECT_EQ(errorOf([&] { buildHandedOver(grid); }), viewedError);
  grid.connectivity[41] = 0;
  const std::string laterError = errorOf([&] { buildMesh(UnstructuredGrid(grid), "handed.vtu"); });
  EXPECT_NE(laterError.find("cell 25: point index"), std::string::npos) << laterError;
  EXPECT_EQ(errorOf([&] { buildHandedOver(grid); }), laterError);
  for (int64_t &id : grid.connectivity)
    id = std::min<int64_t>(std::max<int64_t>(id, 0), int64_t(grid.points.size()) - 1);
  const std::string fieldError = errorOf([&] { buildMesh(UnstructuredGrid(grid), "handed.vtu"); });
  EXPECT_NE(fieldError.find("values for"), std::string::npos) << fieldError;
  EXPECT_EQ(errorOf([&] { buildHandedOver(grid); }), fieldError);
}

// uvr writes .umesh with points numbered by first use, and reading keeps such a file's order as it is; any
// other numbering is reordered as buildMesh orders every mesh.
TEST_F(Formats, UmeshOrderIsKeptWhenPointsAreNumberedByFirstUse) {
  Mesh mesh = withoutCellFields(mixedMesh());
  UninitVector<uint32_t> reversed; // the hexes in reverse order: no longer along the Morton curve
  for (size_t h = mesh.hexes.size(); h > 0; h -= 8)
    reversed.insert(reversed.end(), mesh.hexes.begin() + std::ptrdiff_t(h - 8),
                    mesh.hexes.begin() + std::ptrdiff_t(h));
  mesh.hexes = reversed;
  Mesh renumbered = mesh;
  std::vector<uint32_t> newIndex(mesh.points.size(), UINT32_MAX);
  uint32_t next = 0;
  for (UninitVector<uint32_t> *cells :
       {&renumbered.tets, &renumbered.pyramids, &renumbered.wedges, &renumbered.hexes})
    for (uint32_t &v : *cells) {
      if (newIndex[v] == UINT32_MAX)
        newIndex[v] = next++;
      v = newIndex[v];
    }
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    renumbered.points[newIndex[i]] = mesh.points[i];
    renumbered.fields[0].values[newIndex[i]] = mesh.fields[0].values[i];
  }
  writeUmesh(path("first_use.umesh"), renumbered);
  expectSameMesh(renumbered, readUmesh(path("first_use.umesh")));

  writeUmesh(path("other.umesh"), mesh);
  const Mesh reordered = readUmesh(path("other.umesh"));
  EXPECT_NE(reordered.hexes, mesh.hexes);
  EXPECT_EQ(reordered.hexCount(), mesh.hexCount());
}

// ---- Gmsh ----

namespace {

const std::string kGmsh = std::string(UVR_TEST_DATA) + "/gmsh/";

double totalVolume(const Mesh &mesh) {
  const MeshView view = makeMeshView(mesh, -1);
  double sum = 0.0;
  for (uint64_t c = 0; c < mesh.cellCount(); ++c)
    sum += cellVolume(view, c);
  return sum;
}

template <typename T> std::string bin(T value) { return le(value); }

/// One small mesh in each Gmsh encoding: sparse node tags 10..50, a triangle (skipped), two tets, a scalar
/// $NodeData at two time steps (listed out of order) and a 3-component $ElementData.
std::string gmshFile(bool version4, bool binary) {
  const std::vector<std::array<double, 3>> xyz = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  const std::vector<uint64_t> tags = {10, 20, 30, 40, 50};
  struct Element {
    uint64_t tag;
    int type;
    std::vector<uint64_t> nodes;
  };
  const std::vector<Element> elements = {
      {3, 2, {10, 20, 30}}, {7, 4, {10, 20, 30, 40}}, {9, 4, {20, 30, 40, 50}}};
  std::ostringstream out;
  out.precision(17);
  out << "$MeshFormat\n" << (version4 ? "4.1" : "2.2") << " " << binary << " 8\n";
  if (binary)
    out << bin(int32_t(1)) << "\n";
  out << "$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"all\"\n$EndPhysicalNames\n";
  auto size = [&](uint64_t v) {
    if (binary && version4)
      out << bin(v);
    else
      out << v << (version4 ? " " : "\n");
  };
  if (version4) {
    out << "$Entities\n0 0 1 1\n1 0 0 0 1 1 0 0 0\n1 0 0 0 1 1 1 0 0\n$EndEntities\n$Nodes\n";
    size(1), size(5), size(10), size(50);
    if (binary)
      out << bin(int32_t(3)) << bin(int32_t(1)) << bin(int32_t(0)) << bin(uint64_t(5));
    else
      out << "\n3 1 0 5\n";
    for (uint64_t t : tags)
      binary ? out << bin(t) : out << t << "\n";
    for (const auto &p : xyz)
      binary ? out << bin(p[0]) << bin(p[1]) << bin(p[2]) : out << p[0] << " " << p[1] << " " << p[2] << "\n";
    out << (binary ? "\n" : "") << "$EndNodes\n$Elements\n";
    size(2), size(3), size(3), size(9);
    out << (binary ? "" : "\n");
    for (int block = 0; block < 2; ++block) {
      const size_t first = block == 0 ? 0 : 1, count = block == 0 ? 1 : 2;
      const int type = elements[first].type;
      if (binary)
        out << bin(int32_t(type == 2 ? 2 : 3)) << bin(int32_t(1)) << bin(int32_t(type))
            << bin(uint64_t(count));
      else
        out << (type == 2 ? 2 : 3) << " 1 " << type << " " << count << "\n";
      for (size_t e = first; e < first + count; ++e) {
        binary ? out << bin(elements[e].tag) : out << elements[e].tag;
        for (uint64_t n : elements[e].nodes)
          binary ? out << bin(n) : out << " " << n;
        out << (binary ? "" : "\n");
      }
    }
    out << (binary ? "\n" : "") << "$EndElements\n";
  } else {
    out << "$Nodes\n5\n";
    for (size_t i = 0; i < xyz.size(); ++i)
      binary ? out << bin(int32_t(tags[i])) << bin(xyz[i][0]) << bin(xyz[i][1]) << bin(xyz[i][2])
             : out << tags[i] << " " << xyz[i][0] << " " << xyz[i][1] << " " << xyz[i][2] << "\n";
    out << (binary ? "\n" : "") << "$EndNodes\n$Elements\n3\n";
    if (binary) {
      out << bin(int32_t(2)) << bin(int32_t(1)) << bin(int32_t(2)) << bin(int32_t(3)) << bin(int32_t(1))
          << bin(int32_t(1));
      for (uint64_t n : elements[0].nodes)
        out << bin(int32_t(n));
      out << bin(int32_t(4)) << bin(int32_t(2)) << bin(int32_t(2));
      for (size_t e = 1; e < 3; ++e) {
        out << bin(int32_t(elements[e].tag)) << bin(int32_t(1)) << bin(int32_t(1));
        for (uint64_t n : elements[e].nodes)
          out << bin(int32_t(n));
      }
      out << "\n";
    } else {
      for (const Element &e : elements) {
        out << e.tag << " " << e.type << " 2 1 1";
        for (uint64_t n : e.nodes)
          out << " " << n;
        out << "\n";
      }
    }
    out << "$EndElements\n";
  }
  auto data = [&](const char *section, const char *name, int step, int components,
                  const std::vector<std::pair<uint64_t, std::vector<double>>> &entries) {
    out << "$" << section << "\n1\n\"" << name << "\"\n1\n"
        << step * 0.5 << "\n3\n"
        << step << "\n"
        << components << "\n"
        << entries.size() << "\n";
    for (const auto &[tag, values] : entries) {
      binary ? out << bin(int32_t(tag)) : out << tag;
      for (double v : values)
        binary ? out << bin(v) : out << " " << v;
      out << (binary ? "" : "\n");
    }
    out << (binary ? "\n" : "") << "$End" << section << "\n";
  };
  for (int step : {1, 0}) {
    std::vector<std::pair<uint64_t, std::vector<double>>> entries;
    for (uint64_t t : tags)
      entries.push_back({t, {double(t) * (step + 1)}});
    data("NodeData", "temperature", step, 1, entries);
  }
  data("ElementData", "velocity", 0, 3, {{7, {3, 4, 0}}, {9, {0, 0, -2}}});
  return out.str();
}

void expectSameGrid(const UnstructuredGrid &a, const UnstructuredGrid &b) {
  EXPECT_TRUE(samePoints(a.points, b.points));
  EXPECT_EQ(a.offsets, b.offsets);
  EXPECT_EQ(a.connectivity, b.connectivity);
  EXPECT_EQ(a.types, b.types);
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (size_t f = 0; f < a.fields.size(); ++f) {
    EXPECT_EQ(a.fields[f].name, b.fields[f].name);
    EXPECT_EQ(a.fields[f].values, b.fields[f].values) << a.fields[f].name;
  }
}

} // namespace

TEST(Gmsh, EncodingsOfAGmshMeshAgree) {
  const char *files[] = {"mixed_22_ascii.msh", "mixed_22_binary.msh", "mixed_41_ascii.msh",
                         "mixed_41_binary.msh"};
  // The versions list elements in different orders; the meshes, ordered spatially, are the same.
  const Mesh first = loadMesh(kGmsh + files[0]);
  for (const char *file : files) {
    SCOPED_TRACE(file);
    const Mesh mesh = loadMesh(kGmsh + file);
    expectSameMesh(first, mesh);
    EXPECT_EQ(mesh.points.size(), 83u);
    EXPECT_EQ(mesh.tetCount(), 55u);
    EXPECT_EQ(mesh.hexCount(), 8u);
    EXPECT_EQ(mesh.wedgeCount(), 28u);
    EXPECT_EQ(mesh.pyramidCount(), 4u);
    EXPECT_EQ(mesh.invertedCells, 0u); // Gmsh's prisms are mirrored into VTK's wedges on reading
    EXPECT_NEAR(totalVolume(mesh), 1.5, 1e-5);
  }
}

TEST(Gmsh, SecondOrderCellsByTheirCorners) {
  const Mesh linear = loadMesh(kGmsh + "mixed_41_ascii.msh");
  for (const char *file : {"mixed_order2_41_ascii.msh", "mixed_order2_22_binary.msh"}) {
    SCOPED_TRACE(file);
    const Mesh quadratic = loadMesh(kGmsh + file);
    EXPECT_EQ(quadratic.tets, linear.tets);
    EXPECT_EQ(quadratic.pyramids, linear.pyramids);
    EXPECT_EQ(quadratic.wedges, linear.wedges);
    EXPECT_EQ(quadratic.hexes, linear.hexes);
    // Corners come first (numbered by first use); the mid-edge and face nodes follow, unused.
    ASSERT_GT(quadratic.points.size(), linear.points.size());
    EXPECT_EQ(
        std::memcmp(quadratic.points.data(), linear.points.data(), linear.points.size() * sizeof(Vec3f)), 0);
  }
}

TEST(Gmsh, SharedPetscMeshes) {
  const std::string shared = std::string(UVR_SHARED_DATA) + "/small/";
  const Mesh pyramids = loadMesh(shared + "petsc_pyr_tet.msh"); // format 4.1, ascii
  EXPECT_EQ(pyramids.points.size(), 62u);
  EXPECT_EQ(pyramids.tetCount(), 186u);
  EXPECT_EQ(pyramids.pyramidCount(), 24u);
  const Mesh wedges = loadMesh(shared + "petsc_hybrid_tetwedge.msh"); // format 2.2, ascii
  EXPECT_EQ(wedges.points.size(), 120u);
  EXPECT_EQ(wedges.tetCount(), 99u);
  EXPECT_EQ(wedges.wedgeCount(), 99u);
  EXPECT_EQ(wedges.invertedCells, 0u);
  EXPECT_EQ(loadMesh(shared + "petsc_doublet-tet.msh").tetCount(), 2u);
}

TEST(Gmsh, FieldsAndTimeStepsInEveryEncoding) {
  const fs::path dir = fs::temp_directory_path() / ("uvr_gmsh_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  UnstructuredGrid reference;
  for (bool version4 : {false, true})
    for (bool binary : {false, true}) {
      SCOPED_TRACE(std::string(version4 ? "4.1" : "2.2") + (binary ? " binary" : " ascii"));
      const std::string path = (dir / "fields.msh").string();
      writeBytes(path, gmshFile(version4, binary));
      int steps = 0;
      const UnstructuredGrid grid = readGmsh(path, {}, &steps);
      EXPECT_EQ(steps, 2);
      EXPECT_EQ(grid.types, (std::vector<uint8_t>{5, 10, 10}));
      EXPECT_EQ(grid.offsets, (std::vector<int64_t>{0, 0, 4, 8}));
      EXPECT_EQ(grid.connectivity, (std::vector<int64_t>{0, 1, 2, 3, 1, 2, 3, 4}));
      ASSERT_EQ(grid.fields.size(), 2u);
      EXPECT_EQ(grid.fields[0].name, "temperature");
      EXPECT_EQ(grid.fields[0].values, (UninitVector<float>{10, 20, 30, 40, 50}));
      EXPECT_EQ(grid.fields[1].name, "velocity");
      EXPECT_EQ(grid.fields[1].centering, Centering::Cell);
      EXPECT_EQ(grid.fields[1].values, (UninitVector<float>{0, 5, 2}));
      const UnstructuredGrid second = readGmsh(path, {1});
      EXPECT_EQ(second.fields[0].values, (UninitVector<float>{20, 40, 60, 80, 100}));
      EXPECT_EQ(second.fields[1].values, grid.fields[1].values); // one step only: the same at every step
      EXPECT_NE(errorOf([&] { readGmsh(path, {2}); }).find("time step 2 asked, the file has 2"),
                std::string::npos);
      const Mesh mesh = loadMesh(path, {1});
      EXPECT_EQ(mesh.skippedCells, 1u);
      EXPECT_EQ(mesh.tetCount(), 2u);
      if (reference.points.empty())
        reference = grid;
      else
        expectSameGrid(reference, grid);

      // Cut anywhere (every byte of the head, a stride after), the file gives an error naming a byte, never
      // a crash; only a cut just after a section after $Elements leaves a valid (shorter) file.
      const std::string bytes = gmshFile(version4, binary);
      const size_t elementsEnd = bytes.find("$EndElements\n") + 13;
      for (size_t cut = 0; cut < bytes.size(); cut += cut < 160 ? 1 : 5) {
        const std::string prefix = bytes.substr(0, cut);
        writeBytes(path, prefix);
        const std::string error = errorOf([&] { readGmsh(path); });
        const std::string trimmed = prefix.ends_with("\n") ? prefix.substr(0, prefix.size() - 1) : prefix;
        const std::string lastLine = trimmed.substr(trimmed.rfind('\n') + 1);
        const bool sectionEnd =
            lastLine == "$EndElements" || lastLine == "$EndNodeData" || lastLine == "$EndElementData";
        if (cut + 1 >= elementsEnd && sectionEnd)
          EXPECT_EQ(error, "") << "cut at " << cut;
        else
          EXPECT_NE(error.find(path + ", byte "), std::string::npos) << "cut at " << cut << ": " << error;
      }
    }
  fs::remove_all(dir);
}

TEST_F(Formats, GmshOversizedCountsAndUnknownNodes) {
  const std::string head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  writeBytes(path("huge.msh"), head + "$Nodes\n99999999999\n1 0 0 0\n$EndNodes\n");
  std::string error = errorOf([&] { readGmsh(path("huge.msh")); });
  EXPECT_NE(error.find(", byte 42: 99999999999 nodes declared"), std::string::npos) << error;

  writeBytes(path("binary.msh"), "$MeshFormat\n4.1 1 8\n" + bin(int32_t(1)) + "\n$EndMeshFormat\n$Nodes\n" +
                                     bin(uint64_t(1)) + bin(uint64_t(1) << 60) + bin(uint64_t(1)) +
                                     bin(uint64_t(1)) + "\n$EndNodes\n");
  error = errorOf([&] { readGmsh(path("binary.msh")); });
  EXPECT_NE(error.find(std::to_string(uint64_t(1) << 60) + " nodes declared"), std::string::npos) << error;

  writeBytes(path("unknown.msh"), head + "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                                         "$Elements\n1\n1 4 0 1 2 3 5\n$EndElements\n");
  error = errorOf([&] { loadMesh(path("unknown.msh")); });
  EXPECT_NE(error.find("element 1 names node 5, which $Nodes does not list"), std::string::npos) << error;

  writeBytes(path("type.msh"),
             head + "$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n1\n1 99 0 1\n$EndElements\n");
  error = errorOf([&] { loadMesh(path("type.msh")); });
  EXPECT_NE(error.find("unsupported Gmsh element type 99"), std::string::npos) << error;
}

// ---- Time series ----

namespace {

/// A mesh of one tet whose point field "f" is `value` everywhere.
Mesh tetWithValue(float value) {
  UnstructuredGrid grid;
  grid.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  grid.offsets = {0, 4};
  grid.connectivity = {0, 1, 2, 3};
  grid.types = {10};
  grid.fields = {{"f", Centering::Point, UninitVector<float>(4, value)}};
  return buildMesh(std::move(grid), "tet");
}

} // namespace

TEST_F(Formats, PvdCollectionTimeSteps) {
  for (int i : {0, 1, 2})
    writeVtu(path("step" + std::to_string(i) + ".vtu"), tetWithValue(float(i)));
  fs::create_directories(dir_ / "parts");
  writeVtu(path("parts/a.vtu"), tetWithValue(7.f));
  writeVtu(path("parts/b.vtu"), tetWithValue(8.f));
  // Listed out of time order; the step at t = 0.5 has two parts, which are merged.
  std::ofstream(path("series.pvd"))
      << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
         "<Collection>\n"
         "<DataSet timestep=\"2\" part=\"0\" file=\"step2.vtu\"/>\n"
         "<DataSet timestep=\"0\" part=\"0\" file=\"step0.vtu\"/>\n"
         "<DataSet timestep=\"0.5\" part=\"0\" file=\"parts/a.vtu\"/>\n"
         "<DataSet timestep=\"0.5\" part=\"1\" file=\"parts/b.vtu\"/>\n"
         "<DataSet timestep=\"1\" part=\"0\" file=\"step1.vtu\"/>\n"
         "</Collection>\n</VTKFile>\n";
  EXPECT_EQ(timeStepCount(path("series.pvd")), 4);
  EXPECT_EQ(loadMesh(path("series.pvd")).fields[0].values, UninitVector<float>(4, 0.f));
  const Mesh merged = loadMesh(path("series.pvd"), {1});
  EXPECT_EQ(merged.tetCount(), 2u);
  EXPECT_EQ(merged.points.size(), 8u);
  UninitVector<float> values = merged.fields[0].values;
  std::sort(values.begin(), values.end());
  EXPECT_EQ(values, (UninitVector<float>{7, 7, 7, 7, 8, 8, 8, 8}));
  EXPECT_EQ(loadMesh(path("series.pvd"), {2}).fields[0].values, UninitVector<float>(4, 1.f));
  EXPECT_EQ(loadMesh(path("series.pvd"), {3}).fields[0].values, UninitVector<float>(4, 2.f));
  const std::string error = errorOf([&] { loadMesh(path("series.pvd"), {4}); });
  EXPECT_NE(error.find("time step 4 asked, the series has 4 (0 to 3)"), std::string::npos) << error;
}

TEST_F(Formats, NumberedFileTimeSteps) {
  // Numbers sort by value (2 before 10), with or without zero padding.
  for (int i : {10, 2, 0})
    writeVtu(path("data_" + std::to_string(i) + ".vtu"), tetWithValue(float(i)));
  writeVtu(path("other.vtu"), tetWithValue(-1.f));
  for (const std::string pattern : {"data_%d.vtu", "data_*.vtu"}) {
    SCOPED_TRACE(pattern);
    EXPECT_EQ(timeStepCount(path(pattern)), 3);
    EXPECT_EQ(loadMesh(path(pattern), {1}).fields[0].values, UninitVector<float>(4, 2.f));
    EXPECT_EQ(loadMesh(path(pattern), {2}).fields[0].values, UninitVector<float>(4, 10.f));
  }
  for (int i : {1, 3})
    saveMesh(path("padded_" + std::string(i < 10 ? "000" : "00") + std::to_string(i) + ".umesh"),
             tetWithValue(float(i)));
  EXPECT_EQ(loadMesh(path("padded_%04d.umesh"), {1}).fields[0].values, UninitVector<float>(4, 3.f));
  EXPECT_EQ(timeStepCount(path("data_0.vtu")), 1);
  EXPECT_NE(errorOf([&] { loadMesh(path("none_%d.vtu")); }).find("no file matches this pattern"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { loadMesh(path("data_0.vtu"), {1}); }).find("time step 1 asked, the file has 1"),
            std::string::npos);
}

TEST_F(Formats, GmshFieldWithFewerTimeSteps) {
  auto nodeData = [](const char *name, int step) {
    return std::string("$NodeData\n1\n\"") + name + "\"\n0\n3\n" + std::to_string(step) +
           "\n1\n4\n1 0\n2 0\n3 0\n4 " + std::to_string(step) + "\n$EndNodeData\n";
  };
  writeBytes(path("steps.msh"), "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
                                "4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n" +
                                    nodeData("a", 0) + nodeData("a", 1) + nodeData("a", 2) +
                                    nodeData("b", 0) + nodeData("b", 1));
  EXPECT_EQ(timeStepCount(path("steps.msh")), 3);
  EXPECT_EQ(loadMesh(path("steps.msh"), {1}).fields[1].values.size(), 4u);
  const std::string error = errorOf([&] { loadMesh(path("steps.msh"), {2}); });
  EXPECT_NE(error.find("field 'b' has 2 time steps, step 2 asked"), std::string::npos) << error;
}
