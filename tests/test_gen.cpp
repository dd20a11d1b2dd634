// `uvr gen`: NIfTI and raw volumes, and the meshes made from them (conformity, grading, counts, determinism,
// orientation, sampling).
#include "engine/renderer.h"
#include "gen/mesher.h"
#include "io/volume_io.h"
#include "mesh/mesh_stats.h"
#include <uvr/error.h>
#include <uvr/image.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <unordered_map>

using namespace uvr;

namespace {

namespace fs = std::filesystem;

struct NiftiHeader {
  int16_t dims[3] = {4, 3, 2};
  int16_t datatype = 2;
  int16_t bitpix = 8;
  float pixdim[4] = {1.f, 0.5f, 0.75f, 2.f};
  float slope = 0.f, intercept = 0.f;
  int16_t qformCode = 0, sformCode = 0;
  float quatern[3] = {0, 0, 0}, offset[3] = {0, 0, 0};
  float srow[3][4] = {};
};

std::vector<uint8_t> niftiBytes(const NiftiHeader &h, const std::vector<uint8_t> &voxels) {
  std::vector<uint8_t> bytes(352 + voxels.size(), 0);
  auto put = [&](int offset, auto value) { std::memcpy(bytes.data() + offset, &value, sizeof(value)); };
  put(0, int32_t(348));
  put(40, int16_t(3));
  for (int a = 0; a < 3; ++a)
    put(42 + 2 * a, h.dims[a]);
  for (int a = 3; a < 8; ++a)
    put(42 + 2 * a, int16_t(1));
  put(70, h.datatype);
  put(72, h.bitpix);
  for (int a = 0; a < 4; ++a)
    put(76 + 4 * a, h.pixdim[a]);
  put(108, 352.f);
  put(112, h.slope);
  put(116, h.intercept);
  put(252, h.qformCode);
  put(254, h.sformCode);
  for (int a = 0; a < 3; ++a) {
    put(256 + 4 * a, h.quatern[a]);
    put(268 + 4 * a, h.offset[a]);
    for (int c = 0; c < 4; ++c)
      put(280 + 16 * a + 4 * c, h.srow[a][c]);
  }
  std::memcpy(bytes.data() + 344, "n+1", 4);
  std::copy(voxels.begin(), voxels.end(), bytes.begin() + 352);
  return bytes;
}

std::string writeFile(const std::string &name, const std::vector<uint8_t> &bytes, bool gzip) {
  const std::string path = (fs::temp_directory_path() / ("uvr_test_gen_" + name)).string();
  if (gzip) {
    gzFile f = gzopen(path.c_str(), "wb");
    gzwrite(f, bytes.data(), unsigned(bytes.size()));
    gzclose(f);
  } else {
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char *>(bytes.data()), bytes.size());
  }
  return path;
}

std::vector<uint8_t> rampVoxels(int count) {
  std::vector<uint8_t> v(count);
  for (int i = 0; i < count; ++i)
    v[i] = uint8_t(i * 3);
  return v;
}

void expectNear(Vec3f a, Vec3f b) {
  EXPECT_NEAR(a.x, b.x, 1e-5);
  EXPECT_NEAR(a.y, b.y, 1e-5);
  EXPECT_NEAR(a.z, b.z, 1e-5);
}

/// A float volume of dims³ voxels, values from f(i, j, k), spacing 0.5 × 1 × 0.8 with an offset.
Volume makeVolume(int64_t nx, int64_t ny, int64_t nz, auto &&f) {
  Volume v;
  v.name = "synthetic";
  v.dims = {nx, ny, nz};
  v.values.resize(v.voxelCount());
  for (int64_t k = 0; k < nz; ++k)
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t i = 0; i < nx; ++i)
        v.values[i + nx * (j + ny * k)] = float(f(double(i), double(j), double(k)));
  v.toWorld = {{{0.5, 0, 0, 10.0}, {0, 1.0, 0, -3.0}, {0, 0, 0.8, 1.0}}};
  return v;
}

/// A ball with a steep rim and a bump inside: values vary strongly near the rim and little elsewhere.
Volume ballVolume() {
  return makeVolume(48, 40, 44, [](double i, double j, double k) {
    const double r = std::sqrt((i - 24) * (i - 24) + (j - 20) * (j - 20) + (k - 22) * (k - 22));
    return 100.0 / (1.0 + std::exp((r - 15.0) / 0.7)) + 20.0 * std::exp(-((i - 28) * (i - 28)) / 8.0);
  });
}

double tetOrientedVolume(const Mesh &m, uint64_t t) {
  const uint32_t *v = &m.tets[4 * t];
  auto p = [&](int k) {
    const Vec3f q = m.points[v[k]];
    return std::array<double, 3>{q.x, q.y, q.z};
  };
  const auto a = p(0), b = p(1), c = p(2), d = p(3);
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
               e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]},
               e3[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return (e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0]) +
          e1[2] * (e2[0] * e3[1] - e2[1] * e3[0])) /
         6.0;
}

struct FaceCounts {
  uint64_t interior = 0, boundary = 0, overShared = 0, openBoundaryEdges = 0;
};

/// Counts tet faces by how many cells share them, and boundary edges not closed by an even number of
/// boundary faces (a hanging vertex leaves such edges).
FaceCounts countFaces(const Mesh &m) {
  std::unordered_map<uint64_t, std::pair<std::array<uint32_t, 3>, int>> faces;
  auto key = [](std::array<uint32_t, 3> f) {
    return (uint64_t(f[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(f[1]) * 0xC2B2AE3D27D4EB4Full) ^
           (uint64_t(f[2]) * 0x165667B19E3779F9ull);
  };
  std::map<std::array<uint32_t, 3>, int> exact;
  for (uint64_t t = 0; t < m.tetCount(); ++t)
    for (int f = 0; f < 4; ++f) {
      std::array<uint32_t, 3> face;
      int n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != f)
          face[n++] = m.tets[4 * t + k];
      std::sort(face.begin(), face.end());
      ++exact[face];
    }
  (void)key;
  FaceCounts counts;
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto &[face, count] : exact) {
    if (count == 2)
      ++counts.interior;
    else if (count == 1) {
      ++counts.boundary;
      ++edges[{face[0], face[1]}];
      ++edges[{face[1], face[2]}];
      ++edges[{face[0], face[2]}];
    } else
      ++counts.overShared;
  }
  for (const auto &[edge, count] : edges)
    if (count % 2 != 0)
      ++counts.openBoundaryEdges;
  return counts;
}

} // namespace

TEST(GenVolume, NiftiSpacingAndValues) {
  NiftiHeader h;
  const auto voxels = rampVoxels(24);
  for (bool gzip : {false, true}) {
    const Volume v = readNifti(writeFile(gzip ? "pixdim.nii.gz" : "pixdim.nii", niftiBytes(h, voxels), gzip));
    EXPECT_EQ(v.dims, (std::array<int64_t, 3>{4, 3, 2}));
    EXPECT_EQ(v.name, "uvr_test_gen_pixdim");
    EXPECT_FLOAT_EQ(v.at(3, 2, 1), 69.f);
    EXPECT_FLOAT_EQ(v.at(1, 1, 0), 15.f);
    expectNear(v.world(1, 2, 1), {0.5f, 1.5f, 2.f});
    EXPECT_FLOAT_EQ(v.sample(0.5, 0, 0), 1.5f);
  }
}

TEST(GenVolume, NiftiSform) {
  NiftiHeader h;
  h.sformCode = 2;
  h.qformCode = 1; // the sform wins
  h.quatern[2] = 1.f;
  const float srow[3][4] = {{0, -0.5f, 0, 7}, {0.5f, 0, 0, -2}, {0, 0, 2, 3}};
  std::memcpy(h.srow, srow, sizeof(srow));
  const Volume v = readNifti(writeFile("sform.nii.gz", niftiBytes(h, rampVoxels(24)), true));
  expectNear(v.world(1, 2, 1), {6.f, -1.5f, 5.f});
  EXPECT_NEAR(v.worldDeterminant(), 0.5, 1e-6);
}

TEST(GenVolume, NiftiQformRotationAndQfac) {
  NiftiHeader h;
  h.qformCode = 1;
  h.pixdim[0] = -1.f; // qfac: k runs backwards
  // 90° about z: (b, c, d) = (0, 0, sin 45°).
  h.quatern[2] = float(std::sqrt(0.5));
  h.offset[0] = 1.f;
  h.offset[1] = 2.f;
  h.offset[2] = 3.f;
  const Volume v = readNifti(writeFile("qform.nii", niftiBytes(h, rampVoxels(24)), false));
  // x' = −0.75 j + 1, y' = 0.5 i + 2, z' = −2 k + 3.
  expectNear(v.world(1, 2, 1), {-0.5f, 2.5f, 1.f});
  EXPECT_LT(v.worldDeterminant(), 0.0);
}

TEST(GenVolume, NiftiTypesAndScaling) {
  NiftiHeader h;
  h.datatype = 4; // int16
  h.bitpix = 16;
  h.slope = 0.5f;
  h.intercept = 10.f;
  std::vector<uint8_t> voxels(48);
  for (int i = 0; i < 24; ++i) {
    const int16_t value = int16_t(-100 * i);
    std::memcpy(&voxels[2 * i], &value, 2);
  }
  Volume v = readNifti(writeFile("int16.nii", niftiBytes(h, voxels), false));
  EXPECT_FLOAT_EQ(v.at(3, 0, 0), -150.f + 10.f);
  h.datatype = 16; // float32
  h.bitpix = 32;
  h.slope = 0.f;
  std::vector<uint8_t> floats(96);
  for (int i = 0; i < 24; ++i) {
    const float value = 0.25f * float(i);
    std::memcpy(&floats[4 * i], &value, 4);
  }
  v = readNifti(writeFile("float.nii.gz", niftiBytes(h, floats), true));
  EXPECT_FLOAT_EQ(v.at(2, 1, 1), 0.25f * 18.f);
  h.datatype = 512; // uint16
  h.bitpix = 16;
  std::vector<uint8_t> shorts(48);
  for (int i = 0; i < 24; ++i) {
    const uint16_t value = uint16_t(60000 + i);
    std::memcpy(&shorts[2 * i], &value, 2);
  }
  v = readNifti(writeFile("uint16.nii", niftiBytes(h, shorts), false));
  EXPECT_FLOAT_EQ(v.at(3, 2, 1), 60023.f);
  v = readRawVolume(writeFile("ramp.raw", shorts, false), {4, 3, 2}, VoxelType::UInt16, {1, 2, 3});
  EXPECT_FLOAT_EQ(v.at(3, 2, 1), 60023.f);
  expectNear(v.world(1, 1, 1), {1.f, 2.f, 3.f});
}

TEST(GenVolume, MalformedFilesAreErrors) {
  NiftiHeader h;
  auto bytes = niftiBytes(h, rampVoxels(24));
  EXPECT_THROW(readNifti(writeFile("short.nii", {bytes.begin(), bytes.end() - 5}, false)), Error);
  auto bad = bytes;
  bad[70] = 99; // unknown datatype
  EXPECT_THROW(readNifti(writeFile("type.nii", bad, false)), Error);
  bad = bytes;
  bad[344] = 'x';
  EXPECT_THROW(readNifti(writeFile("magic.nii", bad, false)), Error);
  EXPECT_THROW(readNifti("/nonexistent/volume.nii"), Error);
  // A header that claims 2048³ float voxels over 24 bytes of data: an error once the data runs out, before
  // any allocation of the claimed size (found by fuzz_nifti).
  NiftiHeader huge;
  huge.dims[0] = huge.dims[1] = huge.dims[2] = 2048;
  huge.datatype = 16;
  huge.bitpix = 32;
  EXPECT_THROW(readNifti(writeFile("huge.nii", niftiBytes(huge, rampVoxels(24)), true)), Error);
}

TEST(GenTet, ConformingGradedPositive) {
  const Volume volume = ballVolume();
  GenOptions options;
  options.cells = 40000;
  options.threshold = 50.f;
  options.cellField = true;
  const Mesh mesh = generateTetMesh(volume, options);
  ASSERT_GT(mesh.tetCount(), 0u);
  const FaceCounts faces = countFaces(mesh);
  EXPECT_EQ(faces.overShared, 0u);
  EXPECT_EQ(faces.openBoundaryEdges, 0u);
  EXPECT_EQ(faces.interior * 2 + faces.boundary, 4 * mesh.tetCount());
  EXPECT_GT(faces.interior, faces.boundary);
  for (uint64_t t = 0; t < mesh.tetCount(); ++t)
    ASSERT_GT(tetOrientedVolume(mesh, t), 0.0) << "tet " << t;
  const VolumeStats volumes = volumeStats(mesh);
  EXPECT_GE(volumes.p99 / volumes.p1, 10.0);
  // Every point is used by some cell.
  std::vector<bool> used(mesh.points.size());
  for (uint32_t v : mesh.tets)
    used[v] = true;
  EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
  ASSERT_EQ(mesh.fields.size(), 2u);
  EXPECT_EQ(mesh.fields[0].name, "synthetic");
  EXPECT_EQ(mesh.fields[1].centering, Centering::Cell);
  EXPECT_EQ(mesh.fields[1].values.size(), mesh.tetCount());
  // Cells are kept by the value at their centroid before the jitter; it moves centroids by a hair.
  for (float v : mesh.fields[1].values)
    EXPECT_GE(v, 45.f);
}

TEST(GenTet, CellCountWithinTenPercent) {
  const Volume volume = ballVolume();
  for (uint64_t target : {10000u, 25000u, 80000u}) {
    GenOptions options;
    options.cells = target;
    const Mesh mesh = generateTetMesh(volume, options);
    EXPECT_NEAR(double(mesh.tetCount()), double(target), 0.1 * double(target)) << "target " << target;
  }
}

TEST(GenTet, DeterministicAcrossThreadCounts) {
  const Volume volume = ballVolume();
  GenOptions options;
  options.cells = 30000;
  options.seed = 7;
  const Mesh a = generateTetMesh(volume, options);
  Mesh b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b = generateTetMesh(volume, options);
  }
  EXPECT_EQ(a.tets, b.tets);
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)));
  EXPECT_EQ(a.fields[0].values, b.fields[0].values);
  options.seed = 8; // another seed jitters the same vertices differently
  const Mesh c = generateTetMesh(volume, options);
  EXPECT_EQ(a.tets, c.tets);
  EXPECT_NE(0, std::memcmp(a.points.data(), c.points.data(), a.points.size() * sizeof(Vec3f)));
}

TEST(GenTet, LinearVolumeSampledExactly) {
  // Linear values: trilinear interpolation reproduces them anywhere, so the point field must equal the
  // linear function at each vertex's own position.
  const Volume volume =
      makeVolume(30, 26, 22, [](double i, double j, double k) { return 2 * i + 3 * j - k + 40; });
  GenOptions options;
  options.cells = 20000;
  options.threshold = 60.f;
  options.cellField = true;
  const Mesh mesh = generateTetMesh(volume, options);
  ASSERT_GT(mesh.tetCount(), 1000u);
  const UninitVector<float> &values = mesh.fields[0].values;
  for (size_t p = 0; p < mesh.points.size(); ++p) {
    const Vec3f w = mesh.points[p];
    const double i = (w.x - 10.0) / 0.5, j = (w.y + 3.0) / 1.0, k = (w.z - 1.0) / 0.8;
    ASSERT_NEAR(values[p], 2 * i + 3 * j - k + 40, 2e-3) << "point " << p;
  }
  for (uint64_t t = 0; t < mesh.tetCount(); ++t) {
    double sum = 0;
    for (int k = 0; k < 4; ++k)
      sum += values[mesh.tets[4 * t + k]];
    ASSERT_NEAR(mesh.fields[1].values[t], sum / 4, 2e-3) << "tet " << t;
  }
}

namespace {

/// Jacobian determinants at the 8 corners of a hexahedron (VTK order): all positive for a valid cell.
double minCornerJacobian(const Mesh &m, uint64_t h) {
  const uint32_t *v = &m.hexes[8 * h];
  // Corner c's three edges, towards its neighbours along +r, +s, +t of the reference cube.
  const int next[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                          {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
  double lowest = INFINITY;
  for (int c = 0; c < 8; ++c) {
    const Vec3f o = m.points[v[c]];
    const Vec3f a = m.points[v[next[c][0]]] - o, b = m.points[v[next[c][1]]] - o,
                d = m.points[v[next[c][2]]] - o;
    lowest = std::min(lowest, double(dot(a, cross(b, d))));
  }
  return lowest;
}

} // namespace

// A generated hex mesh holds the cells that pass the threshold alone, in a box it fills partly. With a
// function transparent below the rim and opaque above it, as the brain's binary preset is, `full` at its
// defaults marches each ray from where it crosses the mesh's boundary (its hexahedra's outer faces) to where
// it turns opaque, and takes under 2/5 of `reference`'s samples for the same image; without the crossings it
// marched the empty space in every partition's box.
TEST(GenHex, FullModeMarchesFromTheBoundary) {
  const Volume volume = ballVolume();
  GenOptions options;
  options.cells = 30000;
  options.threshold = 5.f;
  const Mesh mesh = generateHexMesh(volume, options);
  ColorMap binary;
  binary.rgbPoints = {0.f, 0.2f, 0.2f, 0.2f, 100.f, 1.f, 0.9f, 0.8f};
  binary.opacityPoints = {0.f,  0.f,   0.5f, 0.f, 50.f,  0.f, 0.5f, 0.f,
                          70.f, 0.95f, 0.5f, 0.f, 120.f, 1.f, 0.5f, 0.f};
  Renderer renderer(mesh, 0);
  renderer.setTransferFunction(TransferFunction(binary, 0.f, 120.f));
  const Box3f bounds = mesh.bounds();
  const float s1 = defaultStepSize(volumeStats(mesh), bounds);
  Camera camera;
  camera.at = (bounds.lower + bounds.upper) * 0.5f;
  camera.eye = camera.at + Vec3f{0.4f, -0.3f, 1.f} * (2.f * length(bounds.upper - bounds.lower));
  camera.fovy = 30.f;
  auto settings = [&](RenderMode mode) {
    RenderSettings chosen;
    chosen.width = chosen.height = 96;
    chosen.integrator.mode = mode;
    chosen.integrator.s1 = s1;
    chosen.integrator.s2 = mode == RenderMode::Full ? 8.f * s1 : s1;
    chosen.integrator.p = 4.f;
    chosen.integrator.unit = s1;
    chosen.integrator.preintegrate = mode == RenderMode::Full;
    chosen.integrator.followMesh = mode == RenderMode::Full;
    return chosen;
  };
  const Frame reference = renderer.render(camera, settings(RenderMode::Reference));
  const Frame full = renderer.render(camera, settings(RenderMode::Full));
  EXPECT_LT(5 * full.samplesTotal, 2 * reference.samplesTotal);
  EXPECT_GT(ssim(reference.image, full.image), 0.97);
}

TEST(GenHex, ConformingGradedPositiveCounted) {
  const Volume volume = ballVolume();
  for (uint64_t target : {8000u, 30000u}) {
    GenOptions options;
    options.cells = target;
    options.threshold = 50.f;
    const Mesh mesh = generateHexMesh(volume, options);
    EXPECT_NEAR(double(mesh.hexCount()), double(target), 0.1 * double(target));
    EXPECT_EQ(mesh.tetCount(), 0u);
    // Quad faces shared by at most two cells; boundary edges closed.
    const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                             {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    std::map<std::array<uint32_t, 4>, int> shared;
    for (uint64_t h = 0; h < mesh.hexCount(); ++h)
      for (const auto &f : faces) {
        std::array<uint32_t, 4> key;
        for (int k = 0; k < 4; ++k)
          key[k] = mesh.hexes[8 * h + f[k]];
        std::sort(key.begin(), key.end());
        ++shared[key];
      }
    uint64_t interior = 0, boundary = 0, over = 0;
    for (const auto &[key, count] : shared)
      (count == 2 ? interior : count == 1 ? boundary : over)++;
    EXPECT_EQ(over, 0u);
    EXPECT_EQ(2 * interior + boundary, 6 * mesh.hexCount());
    EXPECT_GT(interior, boundary);
    for (uint64_t h = 0; h < mesh.hexCount(); ++h)
      ASSERT_GT(minCornerJacobian(mesh, h), 0.0) << "hex " << h;
    const VolumeStats volumes = volumeStats(mesh);
    EXPECT_GE(volumes.max / volumes.min, 10.0);
  }
}

TEST(GenHex, DeterministicAndLinearExact) {
  const Volume volume =
      makeVolume(30, 26, 22, [](double i, double j, double k) { return 2 * i + 3 * j - k + 40; });
  GenOptions options;
  options.cells = 15000;
  options.threshold = 60.f;
  options.seed = 3;
  const Mesh a = generateHexMesh(volume, options);
  Mesh b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b = generateHexMesh(volume, options);
  }
  EXPECT_EQ(a.hexes, b.hexes);
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)));
  for (size_t p = 0; p < a.points.size(); ++p) {
    const Vec3f w = a.points[p];
    const double i = (w.x - 10.0) / 0.5, j = (w.y + 3.0) / 1.0, k = (w.z - 1.0) / 0.8;
    ASSERT_NEAR(a.fields[0].values[p], 2 * i + 3 * j - k + 40, 2e-3) << "point " << p;
  }
}
