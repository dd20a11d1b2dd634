// Hostile input (issue 31): each class of finding with cases of its own. Memory bombs must be refused
// before they allocate (the tests run with a small memory limit and would take gigabytes otherwise), FIFOs
// before open() blocks, patterns and collections without exponential time or recursion.
#include "core/limits.h"
#include "io/glob.h"
#include "io/mesh_io.h"
#include "io/volume_io.h"
#include <uvr/uvr.h>

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <thread>

using namespace uvr;

namespace {

namespace fs = std::filesystem;

const std::string kShared = std::string(UVR_SHARED_DATA) + "/";
const std::string kTestData = std::string(UVR_TEST_DATA) + "/";

class Hostile : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("uvr_hostile_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    setMemoryLimit(0);
    fs::remove_all(dir_);
  }
  std::string path(const std::string &name) const { return (dir_ / name).string(); }
  std::string write(const std::string &name, const std::string &bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }
  fs::path dir_;
};

/// The message of the uvr::Error that `f` throws; fails the test when it throws none.
std::string errorOf(const std::function<void()> &f) {
  try {
    f();
  } catch (const Error &e) {
    return e.what();
  }
  ADD_FAILURE() << "no uvr::Error thrown";
  return "";
}

std::string zlibBlock(const std::string &raw) {
  uLongf size = compressBound(raw.size());
  std::string out(size, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef *>(out.data()), &size,
                      reinterpret_cast<const Bytef *>(raw.data()), raw.size(), 9),
            Z_OK);
  out.resize(size);
  return out;
}

/// A compressed .vtu of `points` points at the origin and no cells, whose point data names `fields` arrays
/// that all share the points' appended block.
std::string sharedOffsetVtu(uint32_t points, int fields) {
  const std::string raw(size_t(points) * 12, '\0');
  const std::string block = zlibBlock(raw);
  const uint32_t header[4] = {1, uint32_t(raw.size()), uint32_t(raw.size()), uint32_t(block.size())};
  std::string xml = "<VTKFile type=\"UnstructuredGrid\" byte_order=\"LittleEndian\" header_type=\"UInt32\" "
                    "compressor=\"vtkZLibDataCompressor\"><UnstructuredGrid><Piece NumberOfPoints=\"" +
                    std::to_string(points) + "\" NumberOfCells=\"0\"><PointData>";
  for (int f = 0; f < fields; ++f)
    xml += "<DataArray type=\"Float32\" Name=\"f" + std::to_string(f) +
           "\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>";
  xml += "</PointData><Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
         "offset=\"0\"/></Points></Piece></UnstructuredGrid><AppendedData encoding=\"raw\">_";
  return xml + std::string(reinterpret_cast<const char *>(header), sizeof header) + block +
         "</AppendedData></VTKFile>";
}

// --- 3. Patterns: no backtracking --------------------------------------------------------------------------

TEST(NamePattern, MatchesAsTheSeriesDocumentationSays) {
  EXPECT_TRUE(NamePattern("data_%d.vtu").matches("data_12.vtu"));
  EXPECT_FALSE(NamePattern("data_%d.vtu").matches("data_.vtu"));
  EXPECT_FALSE(NamePattern("data_%d.vtu").matches("data_1a.vtu"));
  EXPECT_TRUE(NamePattern("data_%04d.vtu").matches("data_0007.vtu"));
  EXPECT_TRUE(NamePattern("d*_?.vtu").matches("data_x_7.vtu"));
  EXPECT_FALSE(NamePattern("d*_?.vtu").matches("data_77.vtu"));
  EXPECT_TRUE(NamePattern("*").matches(""));
  EXPECT_TRUE(NamePattern("a.b").matches("a.b"));
  EXPECT_FALSE(NamePattern("a.b").matches("axb")); // '.' is itself, not any character
  EXPECT_TRUE(NamePattern("%d%d").matches("12"));
  EXPECT_FALSE(NamePattern("%d%d").matches("1"));
}

TEST(NamePattern, PathologicalPatternsTakeLinearTime) {
  // std::regex took exponential time on these (a*a*a*...b against aaaa...).
  std::string pattern;
  for (int i = 0; i < 200; ++i)
    pattern += "a*";
  const std::string name(20000, 'a');
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(NamePattern(pattern + "b.vtu").matches(name));
  EXPECT_TRUE(NamePattern(pattern + "%d").matches(name + "1"));
  EXPECT_FALSE(NamePattern("%d%d%d%d%d%d%d%d%d%dx").matches(std::string(20000, '1')));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

TEST_F(Hostile, PatternOfManyStarsFailsQuickly) {
  write("aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa.vtu", "");
  std::string pattern;
  for (int i = 0; i < 40; ++i)
    pattern += "a*";
  EXPECT_NE(errorOf([&] { loadMesh(path(pattern + "b.vtu")); }).find("no file matches this pattern"),
            std::string::npos);
}

// --- 3. Non-regular files: refused before open() blocks ---------------------------------------------------

TEST_F(Hostile, FifoIsRefusedByEveryReader) {
  for (const std::string ext : {".vtu", ".vtk", ".msh", ".umesh", ".e", ".pvd", ".json", ".nii"}) {
    const std::string fifo = path("pipe" + ext);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const std::string message = ext == ".json"  ? errorOf([&] { readColorMapFile(fifo); })
                                : ext == ".nii" ? errorOf([&] { readNifti(fifo); })
                                                : errorOf([&] { loadMesh(fifo); });
    EXPECT_NE(message.find("not a regular file"), std::string::npos) << ext << ": " << message;
  }
  // Named by a collection.
  const std::string pvd =
      write("series.pvd", "<VTKFile type=\"Collection\"><Collection>"
                          "<DataSet timestep=\"0\" file=\"pipe.vtu\"/></Collection></VTKFile>");
  EXPECT_NE(errorOf([&] { loadMesh(pvd); }).find("not a regular file"), std::string::npos);
}

// --- 2. Collections: no recursion -------------------------------------------------------------------------

TEST_F(Hostile, CollectionNamingItselfOrAnotherIsRefused) {
  const std::string self =
      write("self.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet file=\"self.pvd\"/></Collection>"
                        "</VTKFile>");
  EXPECT_NE(errorOf([&] { loadMesh(self); }).find("names another collection"), std::string::npos);
  write("a.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet file=\"b.pvd\"/></Collection></VTKFile>");
  write("b.pvd",
        "<VTKFile type=\"Collection\"><Collection><DataSet file=\"./a.PVD\"/></Collection></VTKFile>");
  EXPECT_NE(errorOf([&] { loadMesh(path("a.pvd")); }).find("names another collection"), std::string::npos);
  // A pattern that matches a collection is not followed either.
  EXPECT_NE(errorOf([&] { loadMesh(path("*")); }).find("cannot hold a collection"), std::string::npos);
}

TEST_F(Hostile, CollectionFileNamesAreNoPatterns) {
  fs::copy_file(kShared + "small/pyramid_ug.vtu", path("part_1.vtu"));
  std::string stars;
  for (int i = 0; i < 30; ++i)
    stars += "a*";
  const std::string pvd = write("s.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet file=\"" + stars +
                                             "b.vtu\"/></Collection></VTKFile>");
  EXPECT_NE(errorOf([&] { loadMesh(pvd); }).find("cannot open file"), std::string::npos);
  const std::string numbered = write("n.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet "
                                              "file=\"part_%d.vtu\"/></Collection></VTKFile>");
  EXPECT_NE(errorOf([&] { loadMesh(numbered); }).find("cannot open file"), std::string::npos);
}

// --- 4. Runaway memory ------------------------------------------------------------------------------------

TEST_F(Hostile, ArraysSharingOneCompressedBlockAreBoundedTogether) {
  // Each array alone inflates under 1032:1; forty of them together far over it.
  const std::string vtu = write("shared.vtu", sharedOffsetVtu(200000, 40));
  EXPECT_LT(fs::file_size(vtu), 8000u);
  const std::string message = errorOf([&] { loadMesh(vtu); });
  EXPECT_NE(message.find("1032 times"), std::string::npos) << message;
  // The points alone pass the ratio; with a memory limit below what they decode to, they are refused by it.
  const std::string one = write("one.vtu", sharedOffsetVtu(200000, 0));
  EXPECT_NO_THROW(loadMesh(one));
  setMemoryLimit(1 << 20);
  EXPECT_NE(errorOf([&] { loadMesh(one); }).find("over the memory limit of 1.0 MiB"), std::string::npos);
}

TEST_F(Hostile, CollectionPartsAreBoundedTogether) {
  fs::copy_file(kShared + "small/pyramid_ug.vtu", path("p.vtu"));
  std::string many = "<VTKFile type=\"Collection\"><Collection>";
  for (int i = 0; i < 10000; ++i)
    many += "<DataSet timestep=\"0\" part=\"" + std::to_string(i) + "\" file=\"p.vtu\"/>";
  write("many.pvd", many + "</Collection></VTKFile>");
  EXPECT_NE(errorOf([&] { loadMesh(path("many.pvd")); }).find("more than once"), std::string::npos);

  std::string parts = "<VTKFile type=\"Collection\"><Collection>";
  for (int i = 0; i < 50; ++i) {
    fs::copy_file(kShared + "small/pyramid_ug.vtu", path("q" + std::to_string(i) + ".vtu"));
    parts += "<DataSet timestep=\"0\" file=\"q" + std::to_string(i) + ".vtu\"/>";
  }
  write("parts.pvd", parts + "</Collection></VTKFile>");
  const uint64_t cells = loadMesh(path("parts.pvd")).cellCount();
  EXPECT_EQ(cells, 50 * loadMesh(path("p.vtu")).cellCount());
  setMemoryLimit(4096);
  EXPECT_NE(errorOf([&] { loadMesh(path("parts.pvd")); }).find("memory limit"), std::string::npos);
}

#if UVR_HAVE_NETCDF
TEST_F(Hostile, ExodusFillValuesAreBoundedByTheFile) {
  // netCDF-4 stores nothing for values never written: 10^8 nodes in a file of kilobytes.
  const std::string cdl =
      write("fill.cdl", "netcdf fill {\ndimensions:\n num_dim = 3 ;\n num_nodes = 100000000 ;\n"
                        " num_elem = 1 ;\n num_el_blk = 1 ;\n num_el_in_blk1 = 1 ;\n"
                        " num_nod_per_el1 = 4 ;\nvariables:\n double coordx(num_nodes) ;\n"
                        " double coordy(num_nodes) ;\n double coordz(num_nodes) ;\n"
                        " int connect1(num_el_in_blk1, num_nod_per_el1) ;\n"
                        "  connect1:elem_type = \"TETRA\" ;\ndata:\n connect1 = 1, 2, 3, 4 ;\n}\n");
  const std::string exo = path("fill.e");
  const std::string command = std::string(UVR_NCGEN) + " -k nc4 -o '" + exo + "' '" + cdl + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  ASSERT_LT(fs::file_size(exo), 1u << 20);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(errorOf([&] { loadMesh(exo); }).find("values declared"), std::string::npos);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
}
#endif

/// A NIfTI-1 header of a uint8 volume of `dims`, with voxels at 352; sform rows when `sform` is given.
std::string niftiHeader(int16_t x, int16_t y, int16_t z, const float *sform = nullptr) {
  std::string h(352, '\0');
  auto put = [&](size_t at, const void *v, size_t n) { std::memcpy(&h[at], v, n); };
  const int32_t size = 348;
  put(0, &size, 4);
  const int16_t dims[8] = {3, x, y, z, 1, 1, 1, 1};
  put(40, dims, 16);
  const int16_t type[2] = {2, 8};
  put(70, type, 4);
  const float pixdim[4] = {1, 1, 1, 1};
  put(76, pixdim, 16);
  const float offset = 352;
  put(108, &offset, 4);
  if (sform) {
    const int16_t code = 1;
    put(254, &code, 2);
    put(280, sform, 48);
  }
  h.replace(344, 4, std::string("n+1\0", 4));
  return h;
}

TEST_F(Hostile, NiftiVoxelsAreBoundedBeforeTheyAreRead) {
  // 2^45 voxels claimed: refused by the header check; 32767^2 x 64: by the file size, plain or gzipped.
  const std::string plain = write("big.nii", niftiHeader(32767, 32767, 8) + std::string(1000, '\0'));
  EXPECT_NE(errorOf([&] { readNifti(plain); }).find("1 times"), std::string::npos);
  const std::string gz = path("big.nii.gz");
  gzFile out = gzopen(gz.c_str(), "wb9");
  const std::string bytes = niftiHeader(32767, 32767, 8) + std::string(1 << 20, '\0');
  gzwrite(out, bytes.data(), unsigned(bytes.size()));
  gzclose(out);
  EXPECT_NE(errorOf([&] { readNifti(gz); }).find("1032 times"), std::string::npos);
  // Within the ratio but over the memory limit.
  setMemoryLimit(1 << 20);
  const std::string fits = write("fits.nii", niftiHeader(128, 128, 32) + std::string(128 * 128 * 32, '\1'));
  EXPECT_NE(errorOf([&] { readNifti(fits); }).find("memory limit"), std::string::npos);
  setMemoryLimit(0);
  EXPECT_EQ(readNifti(fits).values.size(), 128u * 128u * 32u);
}

TEST_F(Hostile, DeeplyNestedTransferFunctionJsonIsRefusedBeforeParsing) {
  const std::string deep = write("deep.json", std::string(1 << 20, '[') + std::string(1 << 20, ']'));
  EXPECT_NE(errorOf([&] { readColorMapFile(deep); }).find("nested more than 64 levels"), std::string::npos);
  // Brackets inside strings are text.
  const std::string quoted = write("quoted.json", "[{\"Name\": \"" + std::string(1000, '[') +
                                                      "\", \"RGBPoints\": [0, 0, 0, 0, 1, 1, 1, 1]}]");
  EXPECT_EQ(readColorMapFile(quoted).rgbPoints.size(), 8u);
  const std::string large = write("large.json", "[" + std::string(20 << 20, ' ') + "]");
  EXPECT_NE(errorOf([&] { readColorMapFile(large); }).find("too large"), std::string::npos);
}

VolumeMesh tetMesh(std::vector<double> points, std::vector<float> field = {0.f, 1.f, 2.f, 3.f}) {
  static const std::vector<int64_t> offsets = {0, 4}, connectivity = {0, 1, 2, 3};
  static const std::vector<uint8_t> types = {10};
  MeshArrays arrays;
  arrays.points = ArrayView(std::span<const double>(points), 3);
  arrays.offsets = offsets;
  arrays.connectivity = connectivity;
  arrays.types = types;
  arrays.fields.push_back({"f", Centering::Point, ArrayView(std::span<const float>(field))});
  return VolumeMesh::fromArrays(arrays, "arrays");
}

const std::vector<double> kTet = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};

TEST(HostileFrame, ImageSizeIsBoundedByTheMemoryLimit) {
  VolumeRenderer renderer(tetMesh(kTet), 0);
  renderer.setTransferFunction(builtinColorMap("viridis"), {0.f, 3.f});
  FrameSettings settings;
  settings.width = settings.height = 16384;
  const auto start = std::chrono::steady_clock::now();
  const std::string message =
      errorOf([&] { renderer.render(frameBounds(renderer.mesh().bounds()), settings); });
  EXPECT_NE(message.find("16384x16384 frame needs 8.0 GiB, over the memory limit"), std::string::npos)
      << message;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
  setMemoryLimit(uint64_t(64) << 30);
  settings.width = settings.height = 64; // what the limit lets through renders
  EXPECT_EQ(renderer.render(frameBounds(renderer.mesh().bounds()), settings).image.width, 64);
  setMemoryLimit(0);
}

TEST(MemoryLimit, ParsesSizes) {
  EXPECT_EQ(parseByteSize("4096"), 4096u);
  EXPECT_EQ(parseByteSize("8G"), uint64_t(8) << 30);
  EXPECT_EQ(parseByteSize("512m"), uint64_t(512) << 20);
  for (const char *bad : {"", "G", "-1", "1.5G", "4GB", "0", "99999999999999999999", "20000000T"})
    EXPECT_THROW(parseByteSize(bad), Error) << bad;
}

// --- 5. Silently wrong ------------------------------------------------------------------------------------

TEST(HostileValues, RangeBeyondFloatIsRefusedNotBlack) {
  VolumeRenderer renderer(tetMesh(kTet, {-3e38f, 3e38f, 0.f, 1.f}), 0);
  const std::string message = errorOf(
      [&] { renderer.setTransferFunction(builtinColorMap("viridis"), renderer.mesh().fieldRange(0)); });
  EXPECT_NE(message.find("wider than float"), std::string::npos) << message;
  EXPECT_NO_THROW(renderer.setTransferFunction(builtinColorMap("viridis"), {-1e38f, 1e38f}));
  EXPECT_THROW(renderer.setTransferFunction(builtinColorMap("viridis"), {0.f, NAN}), Error);
}

TEST(HostileValues, ArraysAreCheckedAsTheReadersCheckFiles) {
  for (double bad : {double(NAN), double(INFINITY), -1e39}) {
    std::vector<double> points = kTet;
    points[7] = bad;
    const std::string message = errorOf([&] { tetMesh(points); });
    EXPECT_NE(message.find(std::isfinite(bad) ? "out of float range" : "not finite"), std::string::npos)
        << message;
    EXPECT_NE(message.find("point 2"), std::string::npos) << message;
  }
  // The same check refuses a file's points (shared by buildMesh).
  UninitVector<Vec3f> points(4);
  for (int i = 0; i < 4; ++i)
    points[i] = {float(kTet[3 * i]), float(kTet[3 * i + 1]), float(kTet[3 * i + 2])};
  points[3].y = NAN;
  const std::vector<int64_t> offsets = {0, 4}, connectivity = {0, 1, 2, 3};
  const std::vector<uint8_t> types = {10};
  EXPECT_NE(errorOf([&] {
              buildMesh(std::move(points), CellArraysView{offsets, connectivity, types}, {}, "x");
            }).find("point 3: coordinates are not finite"),
            std::string::npos);
}

TEST_F(Hostile, FieldNameXmlCannotHoldIsRefusedByTheWriter) {
  Mesh mesh = loadMesh(kShared + "small/pyramid_ug.vtu");
  mesh.fields[0].name = std::string("a\0b", 3);
  EXPECT_NE(errorOf([&] { saveMesh(path("nul.vtu"), mesh); }).find("control character 0"), std::string::npos);
  mesh.fields[0].name = "tab\there";
  saveMesh(path("tab.vtu"), mesh);
  EXPECT_EQ(loadMesh(path("tab.vtu")).fields[0].name, "tab\there");
}

TEST_F(Hostile, NiftiWithNonFiniteAffineIsRefused) {
  const float sform[12] = {1, 0, 0, 0, 0, NAN, 0, 0, 0, 0, 1, 0};
  const std::string nan = write("nan.nii", niftiHeader(4, 4, 4, sform) + std::string(64, '\1'));
  EXPECT_NE(errorOf([&] { readNifti(nan); }).find("finite voxel-to-world map"), std::string::npos);
  const float inf[12] = {1, 0, 0, INFINITY, 0, 1, 0, 0, 0, 0, 1, 0};
  const std::string offset = write("inf.nii", niftiHeader(4, 4, 4, inf) + std::string(64, '\1'));
  EXPECT_NE(errorOf([&] { readNifti(offset); }).find("finite voxel-to-world map"), std::string::npos);
}

// --- 6. Messages ------------------------------------------------------------------------------------------

TEST(HostileMessages, DegenerateDataIsNamedAsSuch) {
  const std::vector<double> coincident(12, 2.0);
  const std::string extent = errorOf([&] { VolumeRenderer(tetMesh(coincident), 0); });
  EXPECT_NE(extent.find("zero extent"), std::string::npos) << extent;
  // Flat cells: the median volume is 0, so no default step.
  const std::vector<double> flat = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  VolumeRenderer renderer(tetMesh(flat), 0);
  renderer.setTransferFunction(builtinColorMap("viridis"), {0.f, 3.f});
  FrameSettings settings;
  settings.width = settings.height = 8;
  Camera camera;
  camera.eye = {0.5f, 0.5f, 3.f};
  camera.at = {0.5f, 0.5f, 0.f};
  const std::string step = errorOf([&] { renderer.render(camera, settings); });
  EXPECT_NE(step.find("median cell volume is 0"), std::string::npos) << step;
  settings.s1 = settings.unit = 0.1f; // given a step, it renders
  EXPECT_NO_THROW(renderer.render(camera, settings));
}

TEST_F(Hostile, MessagesQuoteLongInputShortened) {
  const std::string type(16 << 20, 'X');
  const std::string vtu = write("long.vtu", "<VTKFile type=\"" + type + "\"><UnstructuredGrid/></VTKFile>");
  const std::string message = errorOf([&] { loadMesh(vtu); });
  EXPECT_LT(message.size(), 4000u);
  EXPECT_NE(message.find("characters cut"), std::string::npos) << message.substr(0, 300);
}

TEST_F(Hostile, FiniteDoubleBeyondFloatIsCalledOutOfRange) {
  const std::string vtu =
      write("far.vtu",
            "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"2\" "
            "NumberOfCells=\"0\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" "
            "format=\"ascii\">0 0 0 1e300 0 0</DataArray></Points></Piece></UnstructuredGrid></VTKFile>");
  const std::string message = errorOf([&] { loadMesh(vtu); });
  EXPECT_NE(message.find("point 1 is out of float range (1e+300)"), std::string::npos) << message;
}

TEST_F(Hostile, UmeshAsOneOfSeveralPartsIsNotListedAsAccepted) {
  fs::copy_file(kShared + "small/pyramid_ug.vtu", path("a.vtu"));
  write("b.umesh", "x");
  const std::string pvd = write("ab.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet file=\"a.vtu\"/>"
                                          "<DataSet file=\"b.umesh\"/></Collection></VTKFile>");
  const std::string message = errorOf([&] { loadMesh(pvd); });
  EXPECT_NE(message.find("cannot be one of several parts"), std::string::npos) << message;
  EXPECT_EQ(message.find(".umesh or"), std::string::npos) << message;
}

TEST(HostileMessages, LongPathsGiveErrorsNotFilesystemExceptions) {
  const std::string name(5000, 'x');
  EXPECT_NE(errorOf([&] { chooseColorMap(name + ".json"); }).find("cannot open"), std::string::npos);
  EXPECT_NE(errorOf([&] { chooseColorMap("/tmp/" + name); }).find("File name too long"), std::string::npos);
  EXPECT_NE(errorOf([&] { VolumeMesh::load("/tmp/" + name + ".vtu"); }).find("File name too long"),
            std::string::npos);
  EXPECT_THROW(VolumeMesh::load("/tmp/" + name + "%d.vtu"), Error);
}

// --- 1. Threads -------------------------------------------------------------------------------------------

TEST(HostileThreads, OneRendererSharedByThreads) {
  const VolumeMesh mesh = VolumeMesh::load(kShared + "small/pyramid_ug.vtu");
  VolumeRenderer shared(mesh, 0);
  VolumeRenderer alone(mesh, 0);
  const ColorMap maps[2] = {builtinColorMap("viridis"), builtinColorMap("grayscale")};
  const ValueRange range = mesh.fieldRange(0);
  FrameSettings settings;
  settings.width = settings.height = 40;
  settings.s1 = settings.unit = 0.01f;
  const Camera camera = frameBounds(mesh.bounds());
  std::vector<uint8_t> expected[2];
  for (int m = 0; m < 2; ++m) {
    alone.setTransferFunction(maps[m], range);
    expected[m] = alone.render(camera, settings).image.rgb;
  }
  ASSERT_NE(expected[0], expected[1]);
  // Lazily built on first use by whichever thread comes first; each thread's function kept through its
  // frame by a lock of the caller's, which every change of function takes (the renderer serialises its own
  // steps, not a caller's pair of them).
  std::mutex frameLock;
  shared.setTransferFunction(maps[0], range); // nothing built yet
  std::atomic<int> wrong{0}, failed{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 6; ++i) {
        try {
          if (i % 2 == 0) { // unlocked, beside other threads' changes: only the library's own serialisation
            shared.render(camera, settings);
            continue;
          }
          const std::lock_guard<std::mutex> lock(frameLock);
          shared.setTransferFunction(maps[t % 2], range);
          wrong += shared.render(camera, settings).image.rgb != expected[t % 2];
        } catch (...) {
          ++failed;
        }
      }
    });
  for (std::thread &thread : threads)
    thread.join();
  EXPECT_EQ(failed, 0);
  EXPECT_EQ(wrong, 0);
}

} // namespace
