// The .umesh reader and writer, the .vtu writer, the Gmsh reader and time-step series: round trips, files
// laid out by hand from the formats' specifications, and malformed input.
#include "core/error.h"
#include "io/mesh_io.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
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

bool samePoints(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b) {
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
  EXPECT_NE(error.find("--field"), std::string::npos) << error;
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

// uvr writes .umesh with points numbered by first use, and reading keeps such a file's order as it is; any
// other numbering is reordered as buildMesh orders every mesh.
TEST_F(Formats, UmeshOrderIsKeptWhenPointsAreNumberedByFirstUse) {
  Mesh mesh = withoutCellFields(mixedMesh());
  std::vector<uint32_t> reversed; // the hexes in reverse order: no longer along the Morton curve
  for (size_t h = mesh.hexes.size(); h > 0; h -= 8)
    reversed.insert(reversed.end(), mesh.hexes.begin() + std::ptrdiff_t(h - 8),
                    mesh.hexes.begin() + std::ptrdiff_t(h));
  mesh.hexes = reversed;
  Mesh renumbered = mesh;
  std::vector<uint32_t> newIndex(mesh.points.size(), UINT32_MAX);
  uint32_t next = 0;
  for (std::vector<uint32_t> *cells :
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
