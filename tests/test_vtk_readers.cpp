// The VTK readers: VTK-written variants of real files in every supported encoding (tests/data/vtk, made by
// make_vtk_variants.py) against VTK's own reading, the shared data sets, and malformed input.
#include "io/mesh_io.h"
#include <uvr/error.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>

using namespace uvr;

namespace {

namespace fs = std::filesystem;

const std::string kVariants = std::string(UVR_TEST_DATA) + "/vtk/";
const std::string kShared = std::string(UVR_SHARED_DATA) + "/";

UnstructuredGrid readAny(const std::string &path) {
  return path.ends_with(".vtu") ? readVtu(path) : readVtkLegacy(path);
}

std::map<int, uint64_t> typeCounts(const std::vector<uint8_t> &types) {
  std::map<int, uint64_t> counts;
  for (uint8_t type : types)
    ++counts[type];
  return counts;
}

const ScalarField *findField(const UnstructuredGrid &grid, const std::string &name, Centering centering) {
  for (const ScalarField &field : grid.fields)
    if (field.name == name && field.centering == centering)
      return &field;
  return nullptr;
}

/// Float results against VTK's values printed with 9 digits (magnitudes were computed in double).
bool close(float value, double expected) {
  return std::abs(value - expected) <= 1e-6 * std::abs(expected) + 1e-30;
}

/// VTK's reading of a group of variants, as make_vtk_variants.py wrote it.
struct Reference {
  std::vector<std::array<double, 3>> points;
  std::vector<uint8_t> types;
  std::vector<std::vector<int64_t>> cells;
  std::map<std::pair<Centering, std::string>, std::vector<double>> fields;
};

Reference loadReference(const std::string &path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << "missing " << path;
  Reference ref;
  std::string comment, word;
  std::getline(in, comment);
  uint64_t count = 0;
  in >> word >> count;
  ref.points.resize(count);
  for (auto &p : ref.points)
    in >> p[0] >> p[1] >> p[2];
  in >> word >> count;
  for (uint64_t c = 0; c < count; ++c) {
    int type = 0;
    uint64_t n = 0;
    in >> type >> n;
    ref.types.push_back(uint8_t(type));
    ref.cells.emplace_back(n);
    for (int64_t &id : ref.cells.back())
      in >> id;
  }
  std::string centering, name;
  while (in >> word >> centering >> name >> count) {
    std::vector<double> &values =
        ref.fields[{centering == "point" ? Centering::Point : Centering::Cell, name}];
    values.resize(count);
    for (double &v : values)
      in >> v;
  }
  EXPECT_TRUE(in.eof()) << "malformed " << path;
  return ref;
}

void expectMatches(const UnstructuredGrid &grid, const Reference &ref) {
  ASSERT_EQ(grid.points.size(), ref.points.size());
  for (size_t i = 0; i < ref.points.size(); ++i)
    for (int k = 0; k < 3; ++k)
      ASSERT_TRUE(close(grid.points[i][k], ref.points[i][k]))
          << "point " << i << "[" << k << "]: " << grid.points[i][k] << " vs " << ref.points[i][k];

  ASSERT_EQ(grid.types.size(), ref.types.size());
  EXPECT_EQ(typeCounts(grid.types), typeCounts(ref.types));
  ASSERT_EQ(grid.offsets.size(), ref.cells.size() + 1);
  EXPECT_EQ(grid.offsets.front(), 0);
  EXPECT_EQ(uint64_t(grid.offsets.back()), grid.connectivity.size());
  for (size_t c = 0; c < ref.cells.size(); ++c) {
    ASSERT_EQ(grid.types[c], ref.types[c]) << "cell " << c;
    std::vector<int64_t> ids(grid.connectivity.begin() + grid.offsets[c],
                             grid.connectivity.begin() + grid.offsets[c + 1]);
    ASSERT_EQ(ids, ref.cells[c]) << "cell " << c;
  }

  ASSERT_EQ(grid.fields.size(), ref.fields.size());
  for (const auto &[key, values] : ref.fields) {
    const ScalarField *field = findField(grid, key.second, key.first);
    ASSERT_NE(field, nullptr) << "missing field " << key.second;
    ASSERT_EQ(field->values.size(), values.size()) << key.second;
    for (size_t i = 0; i < values.size(); ++i)
      ASSERT_TRUE(close(field->values[i], values[i]))
          << key.second << "[" << i << "]: " << field->values[i] << " vs " << values[i];
  }
}

class VtkVariant : public ::testing::TestWithParam<std::string> {};

/// Files are named <group>__<variant>; <group>.ref.txt holds what VTK reads from each of them.
const std::vector<std::string> kVariantFiles = {
    "uGridEx__ascii.vtu",
    "uGridEx__binary_zlib_h32_id32.vtu",
    "uGridEx__binary_none_h64.vtu",
    "uGridEx__appended_raw_zlib_h64.vtu",
    "uGridEx__appended_raw_none_h32_id32.vtu",
    "uGridEx__appended_base64_zlib_h32.vtu",
    "uGridEx__appended_base64_none_h64.vtu",
    "uGridEx__bigendian_appended_raw_zlib_h64.vtu",
    "uGridEx__bigendian_binary_none_h32.vtu",
    "uGridEx__ascii_v42.vtk",
    "uGridEx__ascii_v51.vtk",
    "uGridEx__binary_v42.vtk",
    "uGridEx__binary_v51.vtk",
    "uGridEx_typed__ascii.vtu",
    "uGridEx_typed__appended_raw_none_h64.vtu",
    "uGridEx_typed__bigendian_appended_base64_zlib_h32.vtu",
    "uGridEx_typed__ascii_v42.vtk",
    "uGridEx_typed__binary_v51.vtk",
    "fieldfile__ascii.vtu",
    "fieldfile__appended_base64_zlib_h64.vtu",
    "fieldfile__ascii_v51.vtk",
    "fieldfile__binary_v42.vtk",
    "fieldfile__binary_v51.vtk",
    "sfepy__appended_raw_zlib_h64.vtu",
    "sfepy__float64_points_binary_zlib_h32.vtu",
    "sfepy__binary_v51.vtk",
    "sfepy__float64_points_binary_v42.vtk",
    "sfepy_pieces__3pieces_appended_raw_zlib_h64.vtu",
    "pyramid__binary_zlib_h64.vtu",
    "pyramid__ascii_v51.vtk",
    "pyramid__metadata_ascii_v51.vtk",
    "pyramid__metadata_binary_v51.vtk",
};

std::string variantName(const ::testing::TestParamInfo<std::string> &info) {
  std::string name = info.param;
  for (char &c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)))
      c = '_';
  return name;
}

std::string readBytes(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A scratch directory for malformed files, removed afterwards.
class MalformedVtk : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("uvr_vtk_readers_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string &name, const std::string &bytes) const {
    std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  /// Writes `name` as the variant `source` with its first `from` replaced by `to`.
  std::string edit(const std::string &source, const std::string &name, const std::string &from,
                   const std::string &to) const {
    std::string bytes = readBytes(kVariants + source);
    size_t at = bytes.find(from);
    EXPECT_NE(at, std::string::npos) << "'" << from << "' not in " << source;
    return write(name, at == std::string::npos ? bytes : bytes.replace(at, from.size(), to));
  }

  /// The error reading `path` gives: it must name the file and a position, and say `what`.
  static void expectError(const std::string &path, const std::string &what) {
    try {
      readAny(path);
      ADD_FAILURE() << path << " loaded without an error";
    } catch (const Error &e) {
      std::string message = e.what();
      EXPECT_EQ(message.rfind(path + ", ", 0), 0u) << message;
      EXPECT_TRUE(message.find(", byte ") != std::string::npos ||
                  message.find(", line ") != std::string::npos)
          << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
  }

  fs::path dir_;
};

/// Standard base64 with '=' padding.
std::string base64(const std::string &bytes) {
  static const char *alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string text;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t bits = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size())
      bits |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size())
      bits |= uint8_t(bytes[i + 2]);
    for (size_t k = 0; k < 4; ++k)
      text += i + k <= bytes.size() ? alphabet[(bits >> (18 - 6 * k)) & 63] : '=';
  }
  return text;
}

/// The values' bytes as this (little-endian) machine stores them.
template <typename T> std::string packed(std::vector<T> values) {
  return {reinterpret_cast<const char *>(values.data()), values.size() * sizeof(T)};
}

/// The brain meshes of shared/data/PROVENANCE.md: tets only, point T1 from 0, cell T1_cell.
void expectBrain(const std::string &path, uint64_t points, uint64_t tets, float maxT1) {
  UnstructuredGrid grid = readVtu(path);
  EXPECT_EQ(grid.points.size(), points);
  EXPECT_EQ(grid.types.size(), tets);
  EXPECT_EQ(typeCounts(grid.types)[10], tets);
  EXPECT_EQ(grid.connectivity.size(), 4 * tets);
  const ScalarField *t1 = findField(grid, "T1", Centering::Point);
  ASSERT_NE(t1, nullptr);
  auto [low, high] = std::minmax_element(t1->values.begin(), t1->values.end());
  EXPECT_EQ(*low, 0.f);
  EXPECT_NEAR(*high, maxT1, 0.01f);
  const ScalarField *t1Cell = findField(grid, "T1_cell", Centering::Cell);
  ASSERT_NE(t1Cell, nullptr);
  EXPECT_EQ(t1Cell->values.size(), tets);
}

} // namespace

TEST_P(VtkVariant, MatchesVtksReading) {
  std::string file = GetParam();
  UnstructuredGrid grid = readAny(kVariants + file);
  expectMatches(grid, loadReference(kVariants + file.substr(0, file.find("__")) + ".ref.txt"));
}

INSTANTIATE_TEST_SUITE_P(Encodings, VtkVariant, ::testing::ValuesIn(kVariantFiles), variantName);

TEST(VtkReaders, EveryFileIsTested) {
  std::set<std::string> tested(std::begin(kVariantFiles), std::end(kVariantFiles));
  for (const auto &entry : fs::directory_iterator(kVariants)) {
    std::string name = entry.path().filename().string();
    if (name.ends_with(".vtu") || name.ends_with(".vtk")) {
      EXPECT_TRUE(tested.count(name)) << name << " is not in kVariantFiles";
    }
  }
}

TEST(VtkReaders, MultiComponentArraysBecomeMagnitudes) {
  UnstructuredGrid grid = readVtu(kVariants + "fieldfile__ascii.vtu");
  const ScalarField *both = findField(grid, "group_and_material", Centering::Cell);
  ASSERT_NE(both, nullptr);
  ASSERT_EQ(both->values.size(), 3u);
  EXPECT_FLOAT_EQ(both->values[1], std::hypot(2.f, 200.f));
}

// Other writers (meshio, for one) encode an uncompressed array's size header apart from its data, each with
// its own '=' padding.
TEST(VtkReaders, Base64HeaderEncodedApart) {
  auto array = [](const char *type, const char *name, int components, const std::string &data) {
    return std::string("<DataArray type=\"") + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
           std::to_string(components) + "\" format=\"binary\">" +
           base64(packed(std::vector<uint32_t>{uint32_t(data.size())})) + base64(data) + "</DataArray>";
  };
  std::string xml =
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">"
      "<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><PointData>" +
      array("Float64", "f", 1, packed(std::vector<double>{1, 2, 3, 4})) + "</PointData><Points>" +
      array("Float32", "p", 3, packed(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1})) +
      "</Points><Cells>" + array("Int32", "connectivity", 1, packed(std::vector<int32_t>{0, 1, 2, 3})) +
      array("Int32", "offsets", 1, packed(std::vector<int32_t>{4})) +
      array("UInt8", "types", 1, packed(std::vector<uint8_t>{10})) +
      "</Cells></Piece></UnstructuredGrid></VTKFile>";
  std::string path =
      (fs::temp_directory_path() / ("uvr_apart_" + std::to_string(::getpid()) + ".vtu")).string();
  std::ofstream(path) << xml;
  UnstructuredGrid grid = readVtu(path);
  fs::remove(path);
  EXPECT_EQ(grid.points.size(), 4u);
  EXPECT_EQ(grid.points[3].z, 1.f);
  EXPECT_EQ(grid.connectivity, (std::vector<int64_t>{0, 1, 2, 3}));
  EXPECT_EQ(grid.types, std::vector<uint8_t>{10});
  ASSERT_EQ(grid.fields.size(), 1u);
  EXPECT_EQ(grid.fields[0].values, (UninitVector<float>{1, 2, 3, 4}));
}

TEST(SharedVtkData, SmallFiles) {
  UnstructuredGrid ugrid = readVtkLegacy(kShared + "small/uGridEx.vtk");
  EXPECT_EQ(ugrid.points.size(), 27u);
  EXPECT_EQ(ugrid.types.size(), 12u); // 2 tets, 2 hexes and 8 lower-dimensional cells, all kept
  EXPECT_EQ(typeCounts(ugrid.types)[10], 2u);
  EXPECT_EQ(typeCounts(ugrid.types)[12], 2u);
  const ScalarField *scalars = findField(ugrid, "scalars", Centering::Point);
  ASSERT_NE(scalars, nullptr);
  EXPECT_EQ(scalars->values.front(), 0.f);
  EXPECT_EQ(scalars->values.back(), 26.f);
  EXPECT_NE(findField(ugrid, "vectors", Centering::Point), nullptr);

  UnstructuredGrid pyramid = readVtu(kShared + "small/pyramid_ug.vtu");
  EXPECT_EQ(pyramid.points.size(), 5u);
  EXPECT_EQ(pyramid.types, std::vector<uint8_t>{14});
  for (const char *name : {"temperature", "pressure", "velocity"})
    EXPECT_NE(findField(pyramid, name, Centering::Point), nullptr) << name;

  UnstructuredGrid field = readVtkLegacy(kShared + "small/fieldfile.vtk");
  EXPECT_EQ(field.points.size(), 18u);
  EXPECT_EQ(field.types, std::vector<uint8_t>(3, 12));
  const ScalarField *material = findField(field, "material", Centering::Cell);
  ASSERT_NE(material, nullptr);
  EXPECT_EQ(material->values, (UninitVector<float>{100.f, 200.f, 300.f}));
  EXPECT_NE(findField(field, "group", Centering::Cell), nullptr);
  EXPECT_NE(findField(field, "group_and_material", Centering::Cell), nullptr);

  UnstructuredGrid cylinder = readVtkLegacy(kShared + "small/sfepy_cylinder.vtk");
  EXPECT_EQ(cylinder.points.size(), 354u);
  EXPECT_EQ(cylinder.types, std::vector<uint8_t>(1348, 10));
  EXPECT_NE(findField(cylinder, "mat_id", Centering::Cell), nullptr);
}

TEST(SharedVtkData, DiskOutRef) {
  UnstructuredGrid grid = readVtu(kShared + "medium/disk_out_ref.vtu");
  EXPECT_EQ(grid.points.size(), 8499u);
  EXPECT_EQ(grid.types, std::vector<uint8_t>(7472, 12));
  for (const char *name : {"Temp", "Pres", "AsH3", "GaMe3", "CH4", "H2"}) {
    const ScalarField *field = findField(grid, name, Centering::Point);
    ASSERT_NE(field, nullptr) << name;
    EXPECT_EQ(field->values.size(), 8499u);
  }
}

TEST(SharedVtkData, Brain857k) {
  expectBrain(kShared + "medium/brain_t1_tet_857k.vtu", 155394, 856630, 124.815f);
}

TEST(SharedVtkData, Brain3M) {
  std::string path = kShared + "large/brain_t1_tet_3M.vtu";
  if (!fs::exists(path))
    GTEST_SKIP() << path << " is absent";
  expectBrain(path, 498850, 3076010, 125.143f);
}

TEST_F(MalformedVtk, MissingFile) {
  std::string path = (dir_ / "absent.vtu").string();
  try {
    readVtu(path);
    ADD_FAILURE() << "no error";
  } catch (const Error &e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot open file: No such file or directory");
  }
}

TEST_F(MalformedVtk, Truncated) {
  // Cut inside the last appended array (the cell types), inside binary points, inside text points.
  std::string vtu = readBytes(kVariants + "sfepy__appended_raw_zlib_h64.vtu");
  expectError(write("cut.vtu", vtu.substr(0, vtu.size() - 60)), "the file ends");
  expectError(write("cut_head.vtu", vtu.substr(0, 300)), "malformed XML");
  expectError(write("empty.vtu", ""), "malformed XML: No document element found"); // nothing to map
  std::string binary = readBytes(kVariants + "sfepy__binary_v51.vtk");
  expectError(write("cut_binary.vtk", binary.substr(0, binary.find("POINTS") + 400)), "file ends before");
  std::string ascii = readBytes(kVariants + "uGridEx__ascii_v42.vtk");
  expectError(write("cut_ascii.vtk", ascii.substr(0, ascii.find("POINTS") + 40)), "the file ends");
}

TEST_F(MalformedVtk, BadBase64) {
  expectError(
      edit("uGridEx__binary_none_h64.vtu", "bad.vtu", "bAAAAAAAAAAAAAAAAACAPw", "bAAAAAAAAAAAAAAAAACA!w"),
      "invalid base64 character");
  expectError(
      edit("uGridEx__appended_base64_zlib_h32.vtu", "bad_appended.vtu", "   _AQAAAACAAAB", "   _AQAA.ACAAAB"),
      "invalid base64 character");
}

TEST_F(MalformedVtk, CorruptZlib) {
  // The first array's zlib stream starts after its 4-word header (one block): break its header bytes.
  std::string bytes = readBytes(kVariants + "uGridEx__appended_raw_zlib_h64.vtu");
  size_t data = bytes.find('_', bytes.find("<AppendedData")) + 1 + 4 * 8;
  bytes[data] = 0;
  bytes[data + 1] = 0;
  expectError(write("zlib.vtu", bytes), "zlib block 0 is corrupt");
}

TEST_F(MalformedVtk, IndexOutOfRange) {
  expectError(edit("uGridEx__ascii_v42.vtk", "index.vtk", "8 0 1 4 3 6 7 10 9", "8 0 1 4 3 6 7 10 27"),
              "point index 27 at entry 7 is outside [0, 27)");
  expectError(edit("uGridEx__ascii_v51.vtk", "index51.vtk", "CONNECTIVITY vtktypeint64\n0 ",
                   "CONNECTIVITY vtktypeint64\n-1 "),
              "point index -1 at entry 0");
  expectError(edit("uGridEx__ascii.vtu", "index.vtu", "0 1 4 3 6 7", "0 1 4 3 6 99"), "point index 99");
}

TEST_F(MalformedVtk, CountLargerThanFile) {
  expectError(edit("uGridEx__binary_v42.vtk", "points.vtk", "POINTS 27", "POINTS 2700000000000"),
              "values declared but the file ends before them");
  expectError(edit("uGridEx__ascii_v42.vtk", "cells.vtk", "CELLS 12 63", "CELLS 12 630000000000"),
              "values declared but the file ends before them");
  expectError(edit("uGridEx__appended_raw_none_h32_id32.vtu", "points.vtu", "NumberOfPoints=\"27\"",
                   "NumberOfPoints=\"2700000000000\""),
              "expected 32400000000000");
  expectError(edit("uGridEx__ascii.vtu", "cells.vtu", "NumberOfCells=\"12\"", "NumberOfCells=\"1200000000\""),
              "too short to hold them");
}

TEST_F(MalformedVtk, OffsetsMustBeMonotonic) {
  expectError(edit("uGridEx__ascii_v51.vtk", "offsets.vtk", "OFFSETS vtktypeint64\n0 8 16",
                   "OFFSETS vtktypeint64\n0 8 6"),
              "OFFSETS decrease at entry 2");
  expectError(edit("uGridEx__ascii.vtu", "offsets.vtu", "8 16 20", "8 6 20"), "offsets decrease");
}

TEST_F(MalformedVtk, NonFiniteCoordinates) {
  expectError(edit("uGridEx__ascii_v42.vtk", "nan.vtk", "POINTS 27 float\n0 0 0", "POINTS 27 float\n0 nan 0"),
              "point 0 is not finite");
  expectError(edit("uGridEx__ascii.vtu", "inf.vtu", "0 0 0 1 0 0", "0 0 0 inf 0 0"), "point 1 is not finite");
}

TEST_F(MalformedVtk, UnsupportedDatasets) {
  expectError(edit("uGridEx__ascii_v42.vtk", "poly.vtk", "UNSTRUCTURED_GRID", "POLYDATA"),
              "unsupported dataset type 'POLYDATA'");
  expectError(edit("uGridEx__ascii.vtu", "image.vtu", "type=\"UnstructuredGrid\"", "type=\"ImageData\""),
              "unsupported dataset type 'ImageData'");
  expectError(edit("uGridEx__ascii_v42.vtk", "keyword.vtk", "POINTS 27", "POINTZ 27"),
              "unknown keyword 'POINTZ'");
  expectError(
      edit("uGridEx__appended_raw_zlib_h64.vtu", "lz4.vtu", "vtkZLibDataCompressor", "vtkLZ4DataCompressor"),
      "unsupported compressor");
  expectError(write("text.vtk", "hello\n"), "expected '# vtk DataFile Version");
}

TEST_F(MalformedVtk, FieldSizeMustMatch) {
  expectError(edit("uGridEx__ascii_v42.vtk", "point_data.vtk", "POINT_DATA 27", "POINT_DATA 26"),
              "POINT_DATA 26 differs from the point count 27");
  expectError(edit("fieldfile__ascii_v51.vtk", "field.vtk", "group 1 3 int", "group 1 2 int"),
              "has 2 tuples, expected 3");
}

// Truncating or corrupting any variant anywhere gives a uvr::Error or a grid, never a crash, a hang or
// another exception.
TEST_F(MalformedVtk, DamagedAnywhere) {
  std::mt19937 random(11);
  for (const std::string &file : kVariantFiles) {
    std::string bytes = readBytes(kVariants + file);
    std::string extension = file.substr(file.rfind('.'));
    for (int trial = 0; trial < 24; ++trial) {
      std::string damaged = bytes;
      if (trial % 2 == 0) {
        damaged.resize(std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(random));
      } else {
        for (int k = 0; k < 4; ++k)
          damaged[std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(random)] = char(random());
      }
      std::string path = write("damaged" + extension, damaged);
      try {
        readAny(path);
      } catch (const Error &) {
      } catch (const std::exception &e) {
        ADD_FAILURE() << file << " trial " << trial << ": " << e.what();
      }
    }
  }
}
