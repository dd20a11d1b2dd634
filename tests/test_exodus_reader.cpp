// The Exodus II reader: small files made with ncgen from tests/data/exodus/*.cdl (netCDF-3 classic and
// netCDF-4), and the real disk_out_ref.ex2 against VTK's conversion of it to .vtu.
#include "io/mesh_io.h"
#include <uvr/error.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

using namespace uvr;

namespace {

namespace fs = std::filesystem;

const std::string kShared = std::string(UVR_SHARED_DATA) + "/";

#if UVR_HAVE_NETCDF

const std::string kCdl = std::string(UVR_TEST_DATA) + "/exodus/";

class ExodusReader : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("uvr_exodus_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// Runs ncgen on tests/data/exodus/`cdl` with netCDF kind `kind` ("nc3", "nc4").
  std::string generate(const std::string &cdl, const std::string &kind, const std::string &name) const {
    std::string path = (dir_ / name).string();
    std::string command = std::string(UVR_NCGEN) + " -k " + kind + " -o '" + path + "' '" + kCdl + cdl + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    return path;
  }

  fs::path dir_;
};

const ScalarField &field(const Mesh &mesh, const std::string &name) {
  int index = mesh.findField(name);
  if (index < 0)
    throw std::runtime_error("no field " + name);
  return mesh.fields[size_t(index)];
}

TEST_F(ExodusReader, BlocksOfEveryVolumeType) {
  std::string path = generate("two_blocks.cdl", "nc3", "two_blocks.e");
  UnstructuredGrid grid = readExodus(path, 0);
  // The SHELL4 block is skipped; the TETRA10 keeps its 4 corners.
  EXPECT_EQ(grid.types, (std::vector<uint8_t>{12, 13, 13, 14, 10}));
  EXPECT_EQ(grid.offsets, (std::vector<int64_t>{0, 8, 14, 20, 25, 29}));
  EXPECT_EQ(std::vector<int64_t>(grid.connectivity.end() - 4, grid.connectivity.end()),
            (std::vector<int64_t>{0, 1, 3, 13}));

  EXPECT_EQ(timeStepCount(path), 3);
  for (int step = 0; step < 3; ++step) {
    Mesh mesh = loadMesh(path, {step});
    EXPECT_EQ(mesh.points.size(), 20u);
    EXPECT_EQ(mesh.tetCount(), 1u);
    EXPECT_EQ(mesh.pyramidCount(), 1u);
    EXPECT_EQ(mesh.wedgeCount(), 2u);
    EXPECT_EQ(mesh.hexCount(), 1u);
    // Point order is the file's in the reader's output (the mesh orders points spatially).
    const UnstructuredGrid stepGrid = readExodus(path, step);
    EXPECT_EQ(stepGrid.points[12].z, 2.f);
    auto gridField = [&](const std::string &name) -> const ScalarField & {
      for (const ScalarField &f : stepGrid.fields)
        if (f.name == name)
          return f;
      throw Error("no field " + name);
    };
    const ScalarField &temperature = gridField("temperature");
    ASSERT_EQ(temperature.values.size(), 20u);
    EXPECT_EQ(temperature.centering, Centering::Point);
    for (int n = 0; n < 20; ++n)
      EXPECT_EQ(temperature.values[size_t(n)], float(10 * n + step));
    EXPECT_EQ(gridField("pressure").values[19], float(100 * step + 19));

    // Mesh order is tets, pyramids, wedges, hexes; density is the block's base value + step.
    const float s = float(step);
    EXPECT_EQ(field(mesh, "density").values, (UninitVector<float>{5 + s, 4 + s, 2 + s, 3 + s, 1 + s}));
    const UninitVector<float> &stress = field(mesh, "stress").values; // only the hex block has it
    ASSERT_EQ(stress.size(), 5u);
    for (int c = 0; c < 4; ++c)
      EXPECT_TRUE(std::isnan(stress[size_t(c)]));
    EXPECT_EQ(stress[4], 7 + s);
  }
}

TEST_F(ExodusReader, TimeStepOutOfRange) {
  std::string path = generate("two_blocks.cdl", "nc3", "two_blocks.exo");
  for (int step : {3, -1}) {
    try {
      readExodus(path, step);
      ADD_FAILURE() << "time step " << step << " accepted";
    } catch (const Error &e) {
      EXPECT_EQ(std::string(e.what()), path + ", dimension 'time_step': time step " + std::to_string(step) +
                                           " is out of range: the file has 3 time steps (0..2)");
    }
  }
}

TEST_F(ExodusReader, NetCdf4OlderLayout) {
  std::string path = generate("tets_nc4.cdl", "nc4", "tets.ex2");
  std::string magic(4, '\0');
  std::FILE *file = std::fopen(path.c_str(), "rb");
  ASSERT_NE(file, nullptr);
  ASSERT_EQ(std::fread(magic.data(), 1, 4, file), 4u);
  std::fclose(file);
  EXPECT_EQ(magic, "\x89HDF"); // really netCDF-4

  Mesh mesh = loadMesh(path, {1});
  EXPECT_EQ(mesh.tetCount(), 2u);
  EXPECT_EQ(mesh.points[4].x, 1.f);
  EXPECT_EQ(field(mesh, "u").values, (UninitVector<float>{10, 11, 12, 13, 14}));
  EXPECT_EQ(field(mesh, "v").values, (UninitVector<float>{-10, -11, -12, -13, -14}));
  EXPECT_EQ(field(mesh, "id").values, (UninitVector<float>{2, 3}));
  EXPECT_EQ(field(mesh, "u").centering, Centering::Point);
  EXPECT_EQ(field(mesh, "id").centering, Centering::Cell);
}

TEST(SharedExodusData, DiskOutRefMatchesVtkConversion) {
  Mesh exodus = loadMesh(kShared + "medium/disk_out_ref.ex2");
  Mesh vtu = loadMesh(kShared + "medium/disk_out_ref.vtu");
  EXPECT_EQ(exodus.points.size(), 8499u);
  EXPECT_EQ(exodus.hexCount(), 7472u);
  EXPECT_EQ(exodus.cellCount(), 7472u);
  // VTK's Exodus reader numbers the points in another order: compare each point's coordinates and values.
  const std::vector<std::string> names = {"Temp", "Pres", "AsH3", "GaMe3", "CH4", "H2"};
  auto rows = [&](const Mesh &mesh) {
    std::vector<std::vector<float>> result;
    for (size_t i = 0; i < mesh.points.size(); ++i) {
      std::vector<float> row = {mesh.points[i].x, mesh.points[i].y, mesh.points[i].z};
      for (const std::string &name : names)
        row.push_back(field(mesh, name).values.at(i));
      result.push_back(row);
    }
    std::sort(result.begin(), result.end());
    return result;
  };
  EXPECT_EQ(rows(exodus), rows(vtu));
  EXPECT_NE(exodus.findField("VX"), -1);
}

#else

TEST(ExodusReader, RefusedWithoutNetCdf) {
  try {
    readExodus(kShared + "medium/disk_out_ref.ex2", 0);
    ADD_FAILURE() << "no error";
  } catch (const Error &e) {
    EXPECT_NE(std::string(e.what()).find("built without netCDF"), std::string::npos) << e.what();
  }
}

#endif

} // namespace
