// Implicit isosurfaces: where they are found, that they are closed, what skipping keeps, and that the
// backends agree.
#include "engine/renderer.h"
#include "mesh/procedural_mesh.h"

#include <uvr/settings.h>
#include <uvr/system.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

using namespace uvr;

namespace {

const Box3f kBox{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};

/// Transparent everywhere: the surfaces alone are drawn, whether the volume is hidden or not.
TransferFunction transparent() {
  ColorMap map;
  map.rgbPoints = {0.f, 0.2f, 0.4f, 0.8f, 1.f, 0.9f, 0.6f, 0.3f};
  map.opacityPoints = {0.f, 0.f, 0.5f, 0.f, 1.f, 0.f, 0.5f, 0.f};
  return TransferFunction(map, 0.f, 1.f);
}

/// Translucent everywhere.
TransferFunction translucent() {
  ColorMap map;
  map.rgbPoints = {0.f, 0.2f, 0.4f, 0.8f, 1.f, 0.9f, 0.6f, 0.3f};
  map.opacityPoints = {0.f, 0.05f, 0.5f, 0.f, 1.f, 0.05f, 0.5f, 0.f};
  return TransferFunction(map, 0.f, 1.f);
}

/// f = 0.5 + 0.3 x - 0.2 y + 0.4 z: its isosurfaces are planes, and where a ray meets each is known.
struct LinearField {
  Vec3f slope{0.3f, -0.2f, 0.4f};
  float operator()(Vec3f p) const { return 0.5f + dot(slope, p); }
  /// Where `ray` meets the surface f = value.
  float along(const Ray &ray, float value) const {
    return (value - (*this)(ray.origin)) / dot(slope, ray.direction);
  }
  /// The field on jittered tets.
  Mesh mesh() const { return buildMesh(makeBoxGrid(CellType::Tetra, 10, kBox, *this, 0.3f), "box"); }
};

/// Well inside kBox, away from its faces.
bool wellInside(Vec3f p) { return std::fabs(p.x) < 0.9f && std::fabs(p.y) < 0.9f && std::fabs(p.z) < 0.9f; }

RenderSettings isoFrame(std::initializer_list<float> values, RenderMode mode = RenderMode::Full,
                        bool hideVolume = true, int size = 64) {
  RenderSettings settings;
  settings.width = settings.height = size;
  settings.integrator.mode = mode;
  settings.integrator.s1 = 0.02f;
  settings.integrator.s2 = 0.1f;
  settings.integrator.p = 4.f;
  settings.integrator.unit = 0.02f;
  IsoSettings &iso = settings.iso;
  for (const float value : values) {
    iso.values[iso.count] = value;
    iso.colors[iso.count++] = {0.8f, 0.8f, 0.8f};
  }
  iso.hideVolume = hideVolume;
  return settings;
}

Camera cameraAt(Vec3f eye) {
  Camera camera;
  camera.eye = eye;
  camera.at = {0.f, 0.f, 0.f};
  camera.up = std::fabs(eye.y) > 0.9f * length(eye) ? Vec3f{1.f, 0.f, 0.f} : Vec3f{0.f, 1.f, 0.f};
  return camera;
}

/// The distance from the line of `ray` to the origin.
float missDistance(const Ray &ray) {
  const Vec3f toCentre = Vec3f{} - ray.origin;
  return length(toCentre - ray.direction * dot(toCentre, ray.direction));
}

} // namespace

TEST(Isosurface, OfALinearFieldIsTheExactPlane) {
  // The surface f = 0.55 of a linear field is a plane, and each ray's distance to it is known. Rays that end
  // just before it see nothing; just past it, the surface.
  const LinearField linear;
  const Mesh mesh = linear.mesh();
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(transparent());
  const float target = 0.55f;
  const Camera camera = cameraAt({0.6f, 0.9f, 4.f});
  for (RenderMode mode : {RenderMode::Reference, RenderMode::Full}) {
    RenderSettings settings = isoFrame({target}, mode, true, 32);
    const CameraView view = makeCameraView(camera, settings.width, settings.height);
    std::vector<float> before(32 * 32), after(32 * 32);
    std::vector<bool> hits(32 * 32);
    int tested = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const Ray ray = view.ray(x, y);
        const float t = linear.along(ray, target);
        const size_t i = size_t(y) * 32 + size_t(x);
        hits[i] = t > 0.f && wellInside(ray.at(t));
        tested += hits[i];
        before[i] = hits[i] ? t * (1.f - 2e-5f) : 0.f;
        after[i] = hits[i] ? t * (1.f + 2e-5f) : 0.f;
      }
    ASSERT_GT(tested, 100);
    settings.rayLimits = before.data();
    const Frame short_ = renderer.render(camera, settings);
    settings.rayLimits = after.data();
    const Frame long_ = renderer.render(camera, settings);
    for (size_t i = 0; i < hits.size(); ++i) {
      if (!hits[i])
        continue;
      EXPECT_EQ(short_.opacity[i], 0.f) << "mode " << modeName(mode) << ", pixel " << i;
      EXPECT_EQ(long_.opacity[i], 1.f) << "mode " << modeName(mode) << ", pixel " << i;
    }
  }
}

TEST(Isosurface, TranslucentPlanesEachLieExactlyWhereTheFieldTakesTheirValue) {
  // The linear field of the test above, three planes of opacity 0.5 a little more than a step apart: rays
  // march on past each, often two in one bracket, and the sampler leaves the tet of the sample to find them.
  // With the volume drawn (transparent) and shaded, it goes back to the sample's tet for its gradient. Each
  // plane is found where the field takes its value: the opacity just before and after it tells.
  const LinearField linear;
  const Mesh mesh = linear.mesh();
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(transparent());
  const float targets[] = {0.55f, 0.57f, 0.59f};
  const Camera camera = cameraAt({0.6f, 0.9f, 4.f});
  for (const bool hideVolume : {true, false}) {
    RenderSettings settings =
        isoFrame({targets[0], targets[1], targets[2]}, RenderMode::Full, hideVolume, 32);
    settings.iso.opacity = 0.5f;
    settings.integrator.shade = !hideVolume;
    const CameraView view = makeCameraView(camera, settings.width, settings.height);
    for (int plane = 0; plane < 3; ++plane) {
      std::vector<float> before(32 * 32), after(32 * 32);
      std::vector<bool> hits(32 * 32);
      int tested = 0;
      for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
          const Ray ray = view.ray(x, y);
          const float t = linear.along(ray, targets[plane]);
          const size_t i = size_t(y) * 32 + size_t(x);
          // The field falls along these rays: the planes of higher value come first.
          const float tFirst = linear.along(ray, targets[2]);
          hits[i] = tFirst > 0.f && wellInside(ray.at(t)) && wellInside(ray.at(tFirst));
          tested += hits[i];
          before[i] = hits[i] ? t * (1.f - 2e-5f) : 0.f;
          after[i] = hits[i] ? t * (1.f + 2e-5f) : 0.f;
        }
      ASSERT_GT(tested, 100);
      settings.rayLimits = before.data();
      const Frame short_ = renderer.render(camera, settings);
      settings.rayLimits = after.data();
      const Frame long_ = renderer.render(camera, settings);
      const int passed = 2 - plane; // planes before this one along the ray
      const float opacityBefore = 1.f - std::pow(0.5f, float(passed));
      const float opacityAfter = 1.f - std::pow(0.5f, float(passed + 1));
      for (size_t i = 0; i < hits.size(); ++i) {
        if (!hits[i])
          continue;
        EXPECT_NEAR(short_.opacity[i], opacityBefore, 1e-5f) << "plane " << plane << ", pixel " << i;
        EXPECT_NEAR(long_.opacity[i], opacityAfter, 1e-5f) << "plane " << plane << ", pixel " << i;
      }
    }
  }
}

TEST(Isosurface, OfASphereIsClosedFromEveryView) {
  // The distance from the centre, meshed into tets (and hexes, whose crossings are bracketed and refined),
  // small partitions: every ray aimed inside the sphere's silhouette meets the surface, every ray that passes
  // outside it does not.
  const float radius = 0.6f;
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, 12, kBox, [](Vec3f p) { return length(p); }, 0.3f),
                                "sphere");
    Renderer renderer(mesh, mesh.findField("f"), 16);
    renderer.setTransferFunction(transparent());
    renderer.prepare(Backend::Cpu);
    ASSERT_GT(renderer.partitionCount(Backend::Cpu), 16u);
    for (RenderMode mode : {RenderMode::Skip, RenderMode::Full}) {
      for (Vec3f eye : {Vec3f{0.f, 0.f, 4.f}, Vec3f{3.f, 1.f, -2.f}, Vec3f{-1.2f, 3.7f, 0.4f},
                        Vec3f{2.3f, -2.3f, 2.3f}}) {
        const Camera camera = cameraAt(eye);
        const RenderSettings settings = isoFrame({radius}, mode);
        const Frame frame = renderer.render(camera, settings);
        const CameraView view = makeCameraView(camera, settings.width, settings.height);
        int inside = 0;
        for (int y = 0; y < settings.height; ++y)
          for (int x = 0; x < settings.width; ++x) {
            const float miss = missDistance(view.ray(x, y));
            const float opacity = frame.opacity[size_t(y) * size_t(settings.width) + size_t(x)];
            if (miss < radius - 0.03f) {
              ++inside;
              ASSERT_EQ(opacity, 1.f)
                  << "a hole: cells " << int(type) << ", mode " << modeName(mode) << ", eye " << eye.x << ","
                  << eye.y << "," << eye.z << ", pixel " << x << "," << y;
            } else if (miss > radius + 0.03f) {
              ASSERT_EQ(opacity, 0.f) << "cells " << int(type) << ", pixel " << x << "," << y;
            }
          }
        EXPECT_GT(inside, 200);
      }
    }
  }
}

TEST(Isosurface, FoundBetweenTheMeshsBoundaryAndTheSamplesAcrossAGap) {
  // Two slabs, z > 0.2 and z < -0.2, and f = z: each ray from above leaves the upper slab and comes back into
  // the mesh across the gap between them. Surfaces a twentieth of a step inside the slabs' faces across the
  // gap lie between a face and the nearest sample of most rays; every ray through the slabs meets them.
  const auto height = [](Vec3f p) { return p.z; };
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(
        keepCells(makeBoxGrid(type, 10, kBox, height), [](Vec3f c) { return std::fabs(c.z) > 0.2f; }),
        "slabs");
    Renderer renderer(mesh, mesh.findField("f"), 64);
    renderer.setTransferFunction(transparent());
    const Camera camera = cameraAt({0.3f, 0.2f, 4.f});
    for (const float face : {0.2f, -0.2f}) {
      RenderSettings settings = isoFrame({face + (face > 0.f ? 0.001f : -0.001f)});
      const Frame frame = renderer.render(camera, settings);
      const CameraView view = makeCameraView(camera, settings.width, settings.height);
      int through = 0;
      for (int y = 0; y < settings.height; ++y)
        for (int x = 0; x < settings.width; ++x) {
          const Ray ray = view.ray(x, y);
          const Vec3f hit = ray.at((face - ray.origin.z) / ray.direction.z);
          if (std::fabs(hit.x) > 0.9f || std::fabs(hit.y) > 0.9f)
            continue;
          ++through;
          ASSERT_EQ(frame.opacity[size_t(y) * size_t(settings.width) + size_t(x)], 1.f)
              << "a hole: cells " << int(type) << ", face " << face << ", pixel " << x << "," << y;
        }
      EXPECT_GT(through, 1000);
    }
  }
}

TEST(Isosurface, SkippingMarchesTransparentPartitionsThatHoldASurface) {
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 12, kBox, [](Vec3f p) { return length(p); }, 0.3f),
                              "sphere");
  Renderer renderer(mesh, mesh.findField("f"), 16);
  renderer.setTransferFunction(transparent());
  const Camera camera = cameraAt({0.f, 0.f, 4.f});
  RenderSettings plain = isoFrame({}, RenderMode::Full, false);
  const Frame empty = renderer.render(camera, plain);
  const uint32_t partitions = renderer.partitionCount(Backend::Cpu);
  EXPECT_EQ(renderer.transparentPartitions(), partitions);
  for (float opacity : empty.opacity)
    ASSERT_EQ(opacity, 0.f);
  // The volume drawn (transparent), with a surface: the partitions it passes through are marched, the
  // others still skipped.
  const Frame surface = renderer.render(camera, isoFrame({0.6f}, RenderMode::Full, false));
  const uint32_t skipped = renderer.transparentPartitions();
  EXPECT_GT(skipped, 0u);
  EXPECT_LT(skipped, partitions);
  uint32_t marked = 0;
  const PartitionMetadata &meta = renderer.metadata();
  const Partitions &parts = renderer.partitions();
  for (uint32_t i = 0; i < partitions; ++i) {
    const bool holds = parts.valueMin[i] <= 0.6f && 0.6f <= parts.valueMax[i];
    EXPECT_EQ(meta.maxOpacity[i] > 0.f, holds) << "partition " << i;
    marked += holds;
  }
  EXPECT_EQ(skipped, partitions - marked);
  EXPECT_EQ(surface.opacity[32 * 64 + 32], 1.f); // the centre pixel
  // Back to no surface: all skipped again.
  renderer.render(camera, plain);
  EXPECT_EQ(renderer.transparentPartitions(), partitions);
}

TEST(Isosurface, CompositesInDepthOrderWithTheVolume) {
  // Two nested spheres in a translucent volume: the outer one, opaque, hides the inner one, and what lies
  // in front of it still tints the image; the volume hidden, only the lit surface is left.
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 12, kBox, [](Vec3f p) { return length(p); }, 0.3f),
                              "sphere");
  Renderer renderer(mesh, mesh.findField("f"), 16);
  renderer.setTransferFunction(translucent());
  const Camera camera = cameraAt({0.f, 0.f, 4.f});
  const size_t centre = 32 * 64 + 32;
  RenderSettings outer = isoFrame({0.7f}, RenderMode::Full, false);
  RenderSettings both = isoFrame({0.3f, 0.7f}, RenderMode::Full, false);
  outer.iso.colors[0] = both.iso.colors[1] = {1.f, 0.f, 0.f};
  both.iso.colors[0] = {0.f, 1.f, 0.f};
  for (bool preintegrate : {false, true}) {
    outer.integrator.preintegrate = both.integrator.preintegrate = preintegrate;
    const Frame a = renderer.render(camera, outer), b = renderer.render(camera, both);
    EXPECT_EQ(a.image.rgb, b.image.rgb) << "the inner surface shows through the outer one";
    EXPECT_EQ(a.opacity[centre], 1.f);
    EXPECT_GT(a.image.rgb[3 * centre + 2], 0) << "the volume in front of the surface adds its blue";
  }
  outer.iso.hideVolume = true;
  const Frame hidden = renderer.render(camera, outer);
  // Red, and the white light's highlight.
  EXPECT_GT(hidden.image.rgb[3 * centre], hidden.image.rgb[3 * centre + 1] + 100);
  EXPECT_EQ(hidden.image.rgb[3 * centre + 1], hidden.image.rgb[3 * centre + 2]);
}

TEST(Isosurface, CudaAgreesWithTheCpu) {
  if (!backendAvailable(Backend::Cuda) || cudaDeviceCount() == 0)
    GTEST_SKIP() << "no CUDA backend or GPU";
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, 12, kBox, [](Vec3f p) { return length(p); }, 0.3f),
                                "sphere");
    Renderer renderer(mesh, mesh.findField("f"), 16);
    renderer.setTransferFunction(translucent());
    for (bool hide : {true, false}) {
      RenderSettings settings = isoFrame({0.35f, 0.7f}, RenderMode::Full, hide);
      settings.iso.opacity = 0.6f;
      const Frame cpu = renderer.render(cameraAt({1.f, 2.f, 3.f}), settings);
      settings.backend = Backend::Cuda;
      const Frame gpu = renderer.render(cameraAt({1.f, 2.f, 3.f}), settings);
      int far = 0;
      for (size_t i = 0; i < cpu.image.rgb.size(); ++i)
        far += std::abs(int(cpu.image.rgb[i]) - int(gpu.image.rgb[i])) > 3;
      EXPECT_LE(far, int(cpu.image.rgb.size() / 200)) << "cells " << int(type) << ", hidden " << hide;
      // Against the host's computation on the GPU's own partitions, which may be numbered differently.
      const PartitionMetadata host =
          computePartitionMetadata(renderer.deviceAcceleration().partitions, translucent(), &settings.iso);
      EXPECT_EQ(renderer.deviceMetadata().maxOpacity, host.maxOpacity)
          << "cells " << int(type) << ", hidden " << hide;
    }
  }
}
