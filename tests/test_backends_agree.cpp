// The CUDA backend against the CPU one, frame by frame, on every cell type and mode. Runs where a GPU is.
#include "engine/renderer.h"
#include "mesh/cell_neighbors.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_neighbors.h"
#include <uvr/error.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

using namespace uvr;

namespace {

bool haveCudaDevice(Renderer &renderer) {
  try {
    renderer.prepare(parseBackend("cuda"));
    return true;
  } catch (const Error &) {
    return false;
  }
}

bool sameBox(const Box3f &a, const Box3f &b) {
  return a.lower.x == b.lower.x && a.lower.y == b.lower.y && a.lower.z == b.lower.z &&
         a.upper.x == b.upper.x && a.upper.y == b.upper.y && a.upper.z == b.upper.z;
}

/// Walks both KD-trees from `a` and `b` down, expecting the same splits and the same partitions below them
/// (the GPU lays nodes out level by level, the host depth first).
void expectSameTree(const Partitions &host, uint32_t a, const Partitions &device, uint32_t b) {
  const KdNode &x = host.nodes[a], &y = device.nodes[b];
  ASSERT_EQ(x.axis, y.axis) << "host node " << a;
  EXPECT_TRUE(sameBox(host.nodeBounds[a], device.nodeBounds[b])) << "host node " << a;
  if (x.axis == KdNode::kLeaf) {
    EXPECT_TRUE(sameBox(host.bounds[x.child], device.bounds[y.child])) << "host partition " << x.child;
    EXPECT_EQ(host.valueMin[x.child], device.valueMin[y.child]) << "host partition " << x.child;
    EXPECT_EQ(host.valueMax[x.child], device.valueMax[y.child]) << "host partition " << x.child;
    EXPECT_EQ(host.cellCounts[x.child], device.cellCounts[y.child]) << "host partition " << x.child;
    return;
  }
  ASSERT_EQ(x.split, y.split) << "host node " << a;
  expectSameTree(host, x.child, device, y.child);
  expectSameTree(host, x.child + 1, device, y.child + 1);
}

/// The GPU's hierarchy is its own: checked for what point location needs of it.
void expectValidBvh(const MeshView &mesh, const Bvh &bvh) {
  std::vector<int> listed(mesh.cellCount(), 0);
  std::vector<uint32_t> pending{0};
  while (!pending.empty()) {
    const BvhNode node = bvh.nodes[pending.back()];
    pending.pop_back();
    if (node.count > 0) {
      EXPECT_LE(node.count, 8u);
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const uint32_t cell = bvh.cellIds[i];
        ++listed[cell];
        Box3f both = node.bounds;
        both.extend(cellBounds(mesh, cell));
        EXPECT_TRUE(sameBox(both, node.bounds)) << "cell " << cell << " outside its leaf";
      }
      continue;
    }
    for (uint32_t child : {node.first, node.first + 1}) {
      Box3f both = node.bounds;
      both.extend(bvh.nodes[child].bounds);
      EXPECT_TRUE(sameBox(both, node.bounds)) << "node " << child << " outside its parent";
      pending.push_back(child);
    }
  }
  for (size_t c = 0; c < listed.size(); ++c)
    ASSERT_EQ(listed[c], 1) << "cell " << c;
}

} // namespace

TEST(BackendsAgree, CudaBuildsTheHostsAccelerationData) {
  for (CellType type : {CellType::Tetra, CellType::Hexahedron, CellType::Wedge}) {
    // Jittered points; the cells of a grid still share many centroid coordinates, which tests the ties.
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, 14, {{-1.f, -1.f, -1.f}, {2.f, 1.f, 1.5f}},
                                    [](Vec3f p) { return 0.5f + 0.4f * std::sin(3.f * p.x) * p.y; }, 0.2f),
                                "box");
    const MeshView view = makeMeshView(mesh, mesh.findField("f"));
    for (uint32_t leafSize : {1u, 7u, 64u}) {
      Renderer renderer(mesh, mesh.findField("f"), leafSize);
      if (!haveCudaDevice(renderer))
        GTEST_SKIP() << "no CUDA GPU here; scripts/gpu-check runs this where there is one";
      const HostAcceleration device = renderer.deviceAcceleration();
      renderer.prepare(Backend::Cpu);
      const Partitions &host = renderer.partitions();
      ASSERT_EQ(device.partitions.count(), host.count()) << "leaf size " << leafSize;
      ASSERT_EQ(device.partitions.nodes.size(), host.nodes.size());
      EXPECT_TRUE(sameBox(device.partitions.rootBounds, host.rootBounds));
      expectSameTree(host, 0, device.partitions, 0);
      EXPECT_EQ(device.tetNeighbors, buildTetNeighbors(mesh));
      // The other cells' walk aids: the host's, uploaded.
      EXPECT_EQ(device.cellNeighbors, buildCellNeighbors(mesh));
      const std::vector<Vec4f> planes = buildCellFacePlanes(view);
      ASSERT_EQ(device.cellFacePlanes.size(), planes.size());
      EXPECT_EQ(std::memcmp(device.cellFacePlanes.data(), planes.data(), planes.size() * sizeof(Vec4f)), 0);
      EXPECT_EQ(device.cellNeighbors.empty(), type == CellType::Tetra);
      const OccupancyGrid grid = buildOccupancyGrid(view);
      EXPECT_EQ(device.occupancy.grid.nx, grid.grid.nx);
      EXPECT_EQ(device.occupancy.grid.ny, grid.grid.ny);
      EXPECT_EQ(device.occupancy.grid.nz, grid.grid.nz);
      EXPECT_EQ(device.occupancy.bits, grid.bits);
      const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
      const SeedGrid seeds = buildSeedGrid(view, neighbors.data());
      EXPECT_EQ(device.seeds.seeds, seeds.seeds);
      // The same faces per voxel with the same octants, in whatever order the atomics filled them.
      ASSERT_EQ(device.seeds.boundaryStart, seeds.boundaryStart);
      auto rows = [](const SeedGrid &grid) {
        std::vector<std::pair<uint32_t, uint8_t>> entries(grid.boundaryFaces.size());
        for (size_t i = 0; i < entries.size(); ++i)
          entries[i] = {grid.boundaryFaces[i], grid.boundaryOctants[i]};
        for (size_t v = 0; v + 1 < grid.boundaryStart.size(); ++v)
          std::sort(entries.begin() + long(grid.boundaryStart[v]),
                    entries.begin() + long(grid.boundaryStart[v + 1]));
        return entries;
      };
      EXPECT_EQ(rows(device.seeds), rows(seeds));
      EXPECT_EQ(seeds.boundaryFaces.empty(), type != CellType::Tetra);
      std::vector<uint32_t> boundary = device.boundaryFaceList; // listed by atomics, in any order
      std::sort(boundary.begin(), boundary.end());
      // Of other cells than tets, the host's list, uploaded.
      EXPECT_EQ(boundary, type == CellType::Tetra
                              ? listBoundaryFaces(neighbors)
                              : listBoundaryCellFaces(view, nullptr, buildCellNeighbors(mesh)));
      expectValidBvh(view, device.bvh);
    }
  }
}

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
      settings.width = 100; // neither rows of 32 pixels nor tiles of 8x4 divide the frame
      settings.height = 61;
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
      // After a transfer-function change the skipping modes draw frames in rows of pixels and in tiles,
      // timing both, and every mode's later frames draw the tiles heaviest first (CudaBackend::render): every
      // one is the same image, to the bit.
      for (int again = 0; again < (skipsSpace(mode) ? 3 : 1); ++again) {
        const Frame next = renderer.render(camera, settings);
        EXPECT_EQ(next.image.rgb, cuda.image.rgb) << "cell type " << int(type) << ", frame " << again;
        EXPECT_EQ(next.opacity, cuda.opacity) << "cell type " << int(type) << ", frame " << again;
        EXPECT_EQ(next.samplesTotal, cuda.samplesTotal) << "cell type " << int(type) << ", frame " << again;
      }
    }
  }
}

TEST(BackendsAgree, CudaShadesAsTheCpu) {
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh =
        buildMesh(makeBoxGrid(
                      type, 12, {{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}},
                      [](Vec3f p) { return 1.f - length(p) + 0.1f * std::sin(5.f * p.x); }, 0.2f),
                  "ball");
    Renderer renderer(mesh, mesh.findField("f"), 16);
    ColorMap map;
    map.rgbPoints = {0.f, 0.f, 0.f, 1.f, 0.5f, 0.f, 1.f, 0.f, 1.f, 1.f, 0.f, 0.f};
    map.opacityPoints = {0.f,  0.f,  0.5f, 0.f, 0.4f, 0.f, 0.5f, 0.f,
                         0.6f, 0.8f, 0.5f, 0.f, 1.f,  1.f, 0.5f, 0.f};
    renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
    if (!haveCudaDevice(renderer))
      GTEST_SKIP() << "no CUDA GPU here; scripts/gpu-check runs this where there is one";
    Camera camera;
    camera.eye = {2.3f, 1.6f, 3.f};
    camera.at = {0.f, 0.f, 0.f};
    for (bool preintegrate : {false, true}) {
      for (bool headlight : {true, false}) {
        RenderSettings settings;
        settings.width = 100;
        settings.height = 61;
        settings.integrator.mode = RenderMode::Full;
        settings.integrator.s1 = 0.02f;
        settings.integrator.s2 = 0.1f;
        settings.integrator.p = 4.f;
        settings.integrator.unit = 0.1f;
        settings.integrator.preintegrate = preintegrate;
        settings.integrator.shade = true;
        settings.shading.headlight = headlight;
        settings.shading.light = {1.f, 1.f, 1.f};
        const Frame cpu = renderer.render(camera, settings);
        settings.backend = Backend::Cuda;
        const Frame cuda = renderer.render(camera, settings);
        EXPECT_GE(ssim(cpu.image, cuda.image), 0.995) << "cell type " << int(type) << ", pre-integrated "
                                                      << preintegrate << ", headlight " << headlight;
      }
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
    // The GPU's own partitions, whose nodes are laid out differently from the host's.
    const PartitionMetadata host = computePartitionMetadata(renderer.deviceAcceleration().partitions, tf);
    const PartitionMetadata device = renderer.deviceMetadata();
    ASSERT_GT(host.transparentCount, 0u);
    ASSERT_LT(host.transparentCount, renderer.partitionCount(Backend::Cuda));
    EXPECT_EQ(device.transparentCount, host.transparentCount);
    EXPECT_EQ(renderer.transparentPartitions(), host.transparentCount);
    ASSERT_EQ(device.maxOpacity.size(), host.maxOpacity.size());
    ASSERT_EQ(device.nodeMaxOpacity.size(), host.nodeMaxOpacity.size());
    for (size_t i = 0; i < host.maxOpacity.size(); ++i) {
      EXPECT_EQ(device.maxOpacity[i], host.maxOpacity[i]) << "partition " << i;
      EXPECT_NEAR(device.sigma[i], host.sigma[i], 1e-5f) << "partition " << i;
    }
    ASSERT_EQ(device.nodeMinSigma.size(), host.nodeMinSigma.size());
    for (size_t i = 0; i < host.nodeMaxOpacity.size(); ++i) {
      EXPECT_EQ(device.nodeMaxOpacity[i], host.nodeMaxOpacity[i]) << "node " << i;
      EXPECT_NEAR(device.nodeMinSigma[i], host.nodeMinSigma[i], 1e-5f) << "node " << i;
    }
    EXPECT_EQ(host.nodeMinSigma[0], kTransparentSigma);
  }
}
