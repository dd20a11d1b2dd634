// The lean memory layout (no walks: every sample's cell from the BVH) draws the default layout's images on
// each backend present, and the statistics that report memory are there.
#include "engine/renderer.h"
#include "mesh/mesh_stats.h"
#include "mesh/procedural_mesh.h"
#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>
#include <uvr/system.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace uvr {
namespace {

const std::string kData = std::string(UVR_TEST_DATA) + "/../../data/";

bool runs(Backend backend) {
  return backendAvailable(backend) && (backend == Backend::Cpu || cudaDeviceCount() > 0);
}

/// Sets the process's layout for the backends prepared in its scope; Auto again after.
struct LayoutScope {
  explicit LayoutScope(MemoryLayout layout) { setMemoryLayout(layout); }
  ~LayoutScope() { setMemoryLayout(MemoryLayout::Auto); }
};

FrameResult renderIn(MemoryLayout layout, const VolumeMesh &mesh, int field, Backend backend, RenderMode mode,
                     const std::string &view) {
  const LayoutScope scope(layout);
  VolumeRenderer renderer(mesh, field);
  renderer.setTransferFunction(builtinColorMap("viridis"), mesh.fieldRange(field));
  FrameSettings settings;
  settings.mode = mode;
  settings.width = settings.height = 96;
  settings.backend = backend;
  return renderer.render(frameBounds(mesh.bounds(), view), settings);
}

TEST(MemoryLayout, LeanDrawsTheDefaultImage) {
  // Tets (whose walks and boundary crossings lean drops) and hexahedra (whose walks it drops).
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, 10, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}},
                                    [](Vec3f p) { return 0.5f + 0.4f * std::sin(3.f * p.x) * p.y; }, 0.2f),
                                "box");
    for (Backend backend : {Backend::Cpu, Backend::Cuda}) {
      if (!runs(backend))
        continue;
      for (MemoryLayout layout : {MemoryLayout::Default, MemoryLayout::Lean}) {
        const LayoutScope scope(layout);
        Renderer renderer(mesh, mesh.findField("f"), 16);
        renderer.setTransferFunction(TransferFunction(builtinColorMap("viridis"), 0.f, 1.f));
        renderer.prepare(backend);
        EXPECT_EQ(renderer.layout(backend), layout);
        if (backend == Backend::Cuda) {
          const HostAcceleration built = renderer.deviceAcceleration();
          EXPECT_EQ(built.tetNeighbors.empty(), layout == MemoryLayout::Lean || type != CellType::Tetra);
          EXPECT_EQ(built.seeds.seeds.empty(), layout == MemoryLayout::Lean);
          EXPECT_GT(built.bvh.nodes.size(), 0u);
        }
        if (layout == MemoryLayout::Default)
          continue;
        for (RenderMode mode : {RenderMode::Reference, RenderMode::Full})
          for (const Vec3f eye : {Vec3f{2.3f, 1.6f, 3.f}, Vec3f{0.1f, 0.2f, 0.3f}}) { // outside, inside
            Camera camera;
            camera.eye = eye;
            camera.at = {0.f, 0.f, -1.f};
            RenderSettings settings;
            settings.width = 80;
            settings.height = 64;
            settings.backend = backend;
            settings.integrator.mode = mode;
            settings.integrator.s1 = 0.02f;
            settings.integrator.s2 = 0.1f;
            settings.integrator.unit = 0.1f;
            const Frame frame = renderer.render(camera, settings);
            // The same cells are found, up to rounding and which cell a point on a shared face is given to.
            const LayoutScope back(MemoryLayout::Default);
            Renderer reference(mesh, mesh.findField("f"), 16);
            reference.setTransferFunction(TransferFunction(builtinColorMap("viridis"), 0.f, 1.f));
            const Frame expected = reference.render(camera, settings);
            EXPECT_GE(ssim(expected.image, frame.image), 0.999)
                << "cell type " << int(type) << ", " << backendName(backend) << ", " << modeName(mode);
            // Skipping, the occupancy grid lets samples near the surface through that the boundary
            // crossings leave out; they find no cell.
            if (mode == RenderMode::Reference)
              EXPECT_EQ(frame.samplesTotal, expected.samplesTotal)
                  << "cell type " << int(type) << ", " << backendName(backend);
          }
      }
    }
  }
}

TEST(MemoryLayout, AutoIsDefaultOnTheHost) {
  const VolumeMesh mesh = VolumeMesh::load(kData + "disk_out_ref.vtu");
  const FrameResult frame =
      renderIn(MemoryLayout::Auto, mesh, mesh.chooseField(""), Backend::Cpu, RenderMode::Full, "+x");
  EXPECT_EQ(frame.stats.memoryLayout, MemoryLayout::Default);
  EXPECT_GT(frame.stats.hostPeakRssBytes, 0u);
  EXPECT_EQ(frame.stats.gpuPeakBytes, 0u);
}

TEST(MemoryLayout, NamesParse) {
  for (MemoryLayout layout : {MemoryLayout::Auto, MemoryLayout::Default, MemoryLayout::Lean})
    EXPECT_EQ(parseMemoryLayout(memoryLayoutName(layout)), layout);
  EXPECT_THROW(parseMemoryLayout("small"), Error);
}

TEST(MemoryLayout, GpuPeakHoldsTheScene) {
  if (!runs(Backend::Cuda))
    GTEST_SKIP() << "no CUDA GPU here; scripts/gpu-scale runs this where there is one";
  const VolumeMesh mesh = VolumeMesh::load(kData + "disk_out_ref.vtu");
  for (MemoryLayout layout : {MemoryLayout::Default, MemoryLayout::Lean}) {
    const FrameResult frame =
        renderIn(layout, mesh, mesh.chooseField(""), Backend::Cuda, RenderMode::Full, "+x");
    EXPECT_GT(frame.stats.gpuSceneBytes, 0u);
    EXPECT_GE(frame.stats.gpuPeakBytes, frame.stats.gpuSceneBytes) << memoryLayoutName(layout);
    EXPECT_GT(frame.stats.hostPeakRssBytes, 0u);
  }
  // Lean keeps less on the GPU.
  const FrameResult def = renderIn(MemoryLayout::Default, mesh, 0, Backend::Cuda, RenderMode::Full, "+x");
  const FrameResult lean = renderIn(MemoryLayout::Lean, mesh, 0, Backend::Cuda, RenderMode::Full, "+x");
  EXPECT_LT(lean.stats.gpuSceneBytes, def.stats.gpuSceneBytes);
}

// One rank at a time, and several at once sharing their passes.
TEST(VolumeStats, SelectRankFindsWhatNthElementFinds) {
  // Spread values, many repeats (all in one radix digit until the last), negatives and zeros.
  std::mt19937_64 random(7);
  for (const int distinct : {1, 3, 1000, 1 << 30}) {
    std::vector<double> values(200000);
    for (double &v : values) {
      const auto k = int64_t(random() % uint64_t(distinct));
      v = distinct == (1 << 30) ? std::ldexp(double(k) - double(distinct / 4), -int(random() % 40))
                                : 1.5 * double(k) - 1.0;
    }
    values[17] = 0.0;
    const std::vector<uint64_t> ranks{0, 1999, 100000, 100001, values.size() - 1};
    for (const uint64_t gather : {uint64_t(16), uint64_t(1) << 22}) { // through every digit, or at once
      const std::vector<double> together = selectRanks(
          values.size(), ranks, [&](uint64_t i) { return values[i]; }, gather);
      for (size_t i = 0; i < ranks.size(); ++i) {
        std::vector<double> sorted = values;
        std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(ranks[i]), sorted.end());
        EXPECT_EQ(selectRank(
                      values.size(), ranks[i], [&](uint64_t v) { return values[v]; }, gather),
                  sorted[ranks[i]])
            << distinct << " distinct, rank " << ranks[i] << ", gathering " << gather;
        EXPECT_EQ(together[i], sorted[ranks[i]])
            << distinct << " distinct, rank " << ranks[i] << " among others, gathering " << gather;
      }
    }
  }
}

} // namespace
} // namespace uvr
