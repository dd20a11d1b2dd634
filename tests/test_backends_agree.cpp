// The CUDA backend against the CPU one, frame by frame, on every cell type and mode. Runs where a GPU is.
#include "core/error.h"
#include "mesh/procedural_mesh.h"
#include "render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace uvr;

namespace {

bool haveCudaDevice(const Renderer &renderer) {
  try {
    renderer.prepare(parseBackend("cuda"));
    return true;
  } catch (const Error &) {
    return false;
  }
}

} // namespace

TEST(BackendsAgree, CudaRendersTheCpuImage) {
  for (CellType type : {CellType::Tetra, CellType::Hexahedron, CellType::Wedge, CellType::Pyramid}) {
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, 9, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}},
                                    [](Vec3f p) { return 0.5f + 0.4f * std::sin(3.f * p.x) * p.y; }, 0.2f),
                                "box");
    Renderer renderer(mesh, mesh.findField("f"), 16);
    ColorMap map;
    map.rgbPoints = {0.f, 0.f, 0.f, 1.f, 0.5f, 0.f, 1.f, 0.f, 1.f, 1.f, 0.f, 0.f};
    map.opacityPoints = {0.f, 0.f, 0.5f, 0.f, 0.5f, 0.f, 0.5f, 0.f, 1.f, 0.9f, 0.5f, 0.f};
    renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
    if (!haveCudaDevice(renderer))
      GTEST_SKIP() << "no CUDA GPU here; scripts/gpu-check runs this where there is one";
    Camera camera;
    camera.eye = {2.3f, 1.6f, 3.f};
    camera.at = {0.f, 0.f, 0.f};
    for (RenderMode mode :
         {RenderMode::Reference, RenderMode::Skip, RenderMode::Adaptive, RenderMode::Full}) {
      RenderSettings settings;
      settings.width = settings.height = 96;
      settings.integrator.mode = mode;
      settings.integrator.s1 = 0.02f;
      settings.integrator.s2 = 0.1f;
      settings.integrator.unit = 0.1f;
      const Frame cpu = renderer.render(camera, settings);
      settings.backend = Backend::Cuda;
      const Frame cuda = renderer.render(camera, settings);
      EXPECT_GE(ssim(cpu.image, cuda.image), 0.995) << "cell type " << int(type) << ", " << modeName(mode);
      double opacityError = 0.0;
      for (size_t i = 0; i < cpu.opacity.size(); ++i)
        opacityError = std::max(opacityError, double(std::fabs(cpu.opacity[i] - cuda.opacity[i])));
      EXPECT_LT(opacityError, 0.02) << "cell type " << int(type) << ", " << modeName(mode);
    }
  }
}

TEST(BackendsAgree, CudaComputesTheHostsPartitionMetadata) {
  const Mesh mesh =
      buildMesh(makeBoxGrid(
                    CellType::Tetra, 12, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}},
                    [](Vec3f p) { return 0.5f + 0.45f * std::sin(2.f * p.x + p.z) * p.y; }, 0.2f),
                "box");
  Renderer renderer(mesh, mesh.findField("f"), 8);
  if (!haveCudaDevice(renderer))
    GTEST_SKIP() << "no CUDA GPU here; scripts/gpu-check runs this where there is one";
  ColorMap map;
  map.rgbPoints = {0.f, 0.f, 0.f, 1.f, 0.5f, 0.f, 1.f, 0.f, 1.f, 1.f, 0.f, 0.f};
  // An opaque band in the middle of the range, then one at the top: some subtrees fully transparent, others
  // with partitions of every opacity below them.
  for (const std::vector<float> &opacity :
       {std::vector<float>{0.f, 0.f, 0.5f, 0.f, 0.4f, 0.f, 0.5f, 0.f, 0.5f, 0.8f, 0.5f, 0.f, 0.6f, 0.f, 0.5f,
                           0.f},
        std::vector<float>{0.f, 0.f, 0.5f, 0.f, 0.9f, 0.f, 0.5f, 0.f, 1.f, 1.f, 0.5f, 0.f}}) {
    map.opacityPoints = opacity;
    const TransferFunction tf(map, 0.f, 1.f);
    renderer.setTransferFunction(tf);
    const PartitionMetadata host = computePartitionMetadata(renderer.partitions(), tf);
    const PartitionMetadata device = renderer.deviceMetadata();
    ASSERT_GT(host.transparentCount, 0u);
    ASSERT_LT(host.transparentCount, renderer.partitions().count());
    EXPECT_EQ(device.transparentCount, host.transparentCount);
    EXPECT_EQ(renderer.transparentPartitions(), host.transparentCount);
    ASSERT_EQ(device.maxOpacity.size(), host.maxOpacity.size());
    ASSERT_EQ(device.nodeMaxOpacity.size(), host.nodeMaxOpacity.size());
    for (size_t i = 0; i < host.maxOpacity.size(); ++i) {
      EXPECT_EQ(device.maxOpacity[i], host.maxOpacity[i]) << "partition " << i;
      EXPECT_NEAR(device.sigma[i], host.sigma[i], 1e-5f) << "partition " << i;
    }
    for (size_t i = 0; i < host.nodeMaxOpacity.size(); ++i)
      EXPECT_EQ(device.nodeMaxOpacity[i], host.nodeMaxOpacity[i]) << "node " << i;
  }
}
