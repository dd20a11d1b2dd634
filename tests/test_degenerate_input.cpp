// Valid meshes with awkward content: NaN scalars and zero-volume or sliver cells render finite pixels, and
// NaN neither poisons a partition's scalar range nor the field's range.
#include "accel/partitions.h"
#include "engine/renderer.h"
#include "mesh/mesh_stats.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace uvr;

namespace {

const Box3f kBox{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};

ColorMap opaqueRamp() {
  ColorMap map;
  map.rgbPoints = {0.f, 0.f, 0.f, 1.f, 1.f, 1.f, 0.f, 0.f};
  map.opacityPoints = {0.f, 0.2f, 0.5f, 0.f, 1.f, 0.9f, 0.5f, 0.f};
  return map;
}

Camera camera() {
  Camera c;
  c.eye = {2.2f, 1.7f, 3.1f};
  c.at = {0.f, 0.f, 0.f};
  c.fovy = 40.f;
  return c;
}

/// Renders field `name` in every mode; every pixel's opacity must be finite and in [0, 1].
void expectFiniteFrames(const Mesh &mesh, const std::string &name, uint64_t &samples) {
  Renderer renderer(mesh, mesh.findField(name), 8);
  renderer.setTransferFunction(TransferFunction(opaqueRamp(), 0.f, 1.f));
  samples = 0;
  for (RenderMode mode : {RenderMode::Reference, RenderMode::Skip, RenderMode::Adaptive, RenderMode::Full}) {
    RenderSettings settings;
    settings.width = settings.height = 48;
    settings.integrator.mode = mode;
    settings.integrator.s1 = 0.02f;
    settings.integrator.s2 = 0.08f;
    settings.integrator.unit = 0.1f;
    const Frame frame = renderer.render(camera(), settings);
    int bad = 0;
    for (float opacity : frame.opacity)
      bad += !(opacity >= 0.f && opacity <= 1.f);
    EXPECT_EQ(bad, 0) << name << " in mode " << modeName(mode);
    samples += frame.samplesTotal;
  }
}

/// A partition's range must be NaN-free: empty (min > max) only where all its cells are NaN.
void expectCleanRanges(const Partitions &parts) {
  for (uint32_t i = 0; i < parts.count(); ++i) {
    EXPECT_FALSE(std::isnan(parts.valueMin[i])) << "partition " << i;
    EXPECT_FALSE(std::isnan(parts.valueMax[i])) << "partition " << i;
  }
}

} // namespace

TEST(NanScalars, RenderFiniteAndKeepRangesClean) {
  UnstructuredGrid grid = makeBoxGrid(
      CellType::Tetra, 8, kBox, [](Vec3f p) { return 0.5f + 0.25f * p.x; }, 0.15f);
  for (ScalarField &field : grid.fields)
    for (size_t i = 0; i < field.values.size(); i += 3)
      field.values[i] = NAN;
  const Mesh mesh = buildMesh(std::move(grid), "nan");

  for (const char *name : {"f", "f_cell"}) {
    const ScalarField &field = mesh.fields[size_t(mesh.findField(name))];
    const ValueRange range = valueRange(field);
    EXPECT_TRUE(std::isfinite(range.min) && std::isfinite(range.max)) << name;
    EXPECT_LT(range.min, range.max) << name;

    const Partitions parts = buildPartitions(makeMeshView(mesh, mesh.findField(name)), 8);
    expectCleanRanges(parts);
    // With a third of the values NaN, every partition of 8 cells still has a finite value somewhere.
    for (uint32_t i = 0; i < parts.count(); ++i)
      EXPECT_LE(parts.valueMin[i], parts.valueMax[i]) << name << " partition " << i;

    uint64_t samples = 0;
    expectFiniteFrames(mesh, name, samples);
    EXPECT_GT(samples, 0u) << name;
  }
}

TEST(NanScalars, AllNanCellsMakeAnEmptyRange) {
  UnstructuredGrid grid = makeBoxGrid(CellType::Hexahedron, 4, kBox, [](Vec3f) { return NAN; });
  const Mesh mesh = buildMesh(std::move(grid), "all nan");
  const Partitions parts = buildPartitions(makeMeshView(mesh, mesh.findField("f_cell")), 4);
  expectCleanRanges(parts);
  const TransferFunction tf(opaqueRamp(), 0.f, 1.f);
  const PartitionMetadata meta = computePartitionMetadata(parts, tf);
  EXPECT_EQ(meta.transparentCount, parts.count()); // nothing to draw, so every partition is skipped
  uint64_t samples = 0;
  expectFiniteFrames(mesh, "f", samples);
}

TEST(DegenerateCells, ZeroVolumeAndSliversRenderFinite) {
  UnstructuredGrid grid = makeBoxGrid(
      CellType::Tetra, 6, kBox, [](Vec3f p) { return 0.5f + 0.4f * p.y; }, 0.1f);
  const size_t basePoints = grid.points.size();
  // Flat cells of every type in the middle of the box, and slivers a hair thick: extra points, extra cells.
  const std::vector<Vec3f> flat = {{-0.5f, -0.5f, 0.1f},        {0.5f, -0.5f, 0.1f}, {0.5f, 0.5f, 0.1f},
                                   {-0.5f, 0.5f, 0.1f},         {0.f, 0.f, 0.1f},    {0.f, 0.f, 0.1f + 1e-7f},
                                   {0.1f, 0.1f, 0.1f - 1e-30f}, {0.2f, 0.2f, 0.1f}};
  for (Vec3f p : flat)
    grid.points.push_back(p);
  auto add = [&](uint8_t type, std::vector<int64_t> corners) {
    for (int64_t &c : corners)
      c += int64_t(basePoints);
    grid.connectivity.insert(grid.connectivity.end(), corners.begin(), corners.end());
    grid.offsets.push_back(int64_t(grid.connectivity.size()));
    grid.types.push_back(type);
  };
  add(10, {0, 1, 2, 3});             // flat tet
  add(10, {0, 1, 2, 5});             // sliver: apex 1e-7 above the base
  add(10, {0, 1, 2, 6});             // sliver: apex 1e-30 below the base (denormal volume)
  add(10, {4, 4, 4, 4});             // one point four times
  add(10, {0, 4, 7, 2});             // four collinear points
  add(14, {0, 1, 2, 3, 4});          // flat pyramid
  add(13, {0, 1, 2, 0, 1, 2});       // wedge of zero height
  add(12, {0, 1, 2, 3, 0, 1, 2, 3}); // hexahedron of zero height
  for (ScalarField &field : grid.fields) {
    if (field.centering == Centering::Point)
      for (Vec3f p : flat)
        field.values.push_back(0.5f + 0.4f * p.y);
    else
      field.values.resize(grid.types.size(), 0.7f);
  }
  const Mesh mesh = buildMesh(std::move(grid), "degenerate");
  EXPECT_EQ(mesh.cellCount(), 6u * 6 * 6 * 6 + 8);
  const VolumeStats volumes = volumeStats(mesh);
  EXPECT_EQ(volumes.min, 0.0);
  EXPECT_TRUE(std::isfinite(volumes.max));
  for (const char *name : {"f", "f_cell"}) {
    uint64_t samples = 0;
    expectFiniteFrames(mesh, name, samples);
    EXPECT_GT(samples, 0u) << name;
  }
}
