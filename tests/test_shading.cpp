// Gradient shading: the gradient per point, and what lighting does to the image.
#include "engine/renderer.h"
#include "mesh/point_gradients.h"
#include "mesh/procedural_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

using namespace uvr;

namespace {

const Box3f kBox{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};

/// Opaque above 0.5, transparent below: an opaque body where the field exceeds 0.5.
TransferFunction opaqueAboveHalf() {
  ColorMap map;
  map.rgbPoints = {0.f, 0.9f, 0.6f, 0.3f, 1.f, 0.9f, 0.6f, 0.3f};
  map.opacityPoints = {0.f,   0.f, 0.5f, 0.f, 0.45f, 0.f, 0.5f, 0.f,
                       0.55f, 1.f, 0.5f, 0.f, 1.f,   1.f, 0.5f, 0.f};
  return TransferFunction(map, 0.f, 1.f);
}

RenderSettings frame(bool shade, bool preintegrate) {
  RenderSettings settings;
  settings.width = settings.height = 64;
  settings.integrator.mode = RenderMode::Full;
  settings.integrator.s1 = 0.02f;
  settings.integrator.s2 = 0.1f;
  settings.integrator.p = 4.f;
  settings.integrator.unit = 0.02f;
  settings.integrator.preintegrate = preintegrate;
  settings.integrator.shade = shade;
  return settings;
}

Camera frontCamera() {
  Camera camera;
  camera.eye = {0.f, 0.f, 5.f};
  camera.at = {0.f, 0.f, 0.f};
  return camera;
}

/// The summed brightness of the pixels of `image` in columns [x0, x1).
double brightness(const Image &image, int x0, int x1) {
  double sum = 0.0;
  for (int y = 0; y < image.height; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c)
        sum += image.pixel(x, y)[c];
  return sum;
}

} // namespace

TEST(PointGradients, ExactForALinearField) {
  const Vec3f slope{2.f, -3.f, 0.5f};
  const auto linear = [&](Vec3f p) { return 1.f + dot(slope, p); };
  for (CellType type : {CellType::Tetra, CellType::Hexahedron, CellType::Wedge}) {
    const Mesh mesh = buildMesh(makeBoxGrid(type, 6, kBox, linear, 0.3f), "box");
    const std::vector<Vec3f> gradients =
        computePointGradients(makeMeshView(mesh, mesh.findField("f")), mesh.points.size());
    ASSERT_EQ(gradients.size(), mesh.points.size());
    for (size_t p = 0; p < gradients.size(); ++p) {
      ASSERT_NEAR(gradients[p].x, slope.x, 1e-3f) << "cell type " << int(type) << ", point " << p;
      ASSERT_NEAR(gradients[p].y, slope.y, 1e-3f) << "cell type " << int(type) << ", point " << p;
      ASSERT_NEAR(gradients[p].z, slope.z, 1e-3f) << "cell type " << int(type) << ", point " << p;
    }
  }
}

TEST(PointGradients, CellDataTakesThePointAveragedField) {
  // Averaged to the points, a linear cell field stays linear inside: the gradient of interior points
  // is the field's (at the boundary, the averages lean inwards).
  const Vec3f slope{1.f, 2.f, -1.f};
  const Mesh mesh =
      buildMesh(makeBoxGrid(CellType::Hexahedron, 8, kBox, [&](Vec3f p) { return dot(slope, p); }), "box");
  const std::vector<Vec3f> gradients =
      computePointGradients(makeMeshView(mesh, mesh.findField("f_cell")), mesh.points.size());
  int interior = 0;
  for (size_t p = 0; p < gradients.size(); ++p) {
    const Vec3f q = mesh.points[p];
    if (std::fabs(q.x) > 0.7f || std::fabs(q.y) > 0.7f || std::fabs(q.z) > 0.7f)
      continue;
    ++interior;
    EXPECT_NEAR(gradients[p].x, slope.x, 1e-3f) << "point " << p;
    EXPECT_NEAR(gradients[p].y, slope.y, 1e-3f) << "point " << p;
    EXPECT_NEAR(gradients[p].z, slope.z, 1e-3f) << "point " << p;
  }
  EXPECT_GT(interior, 0);
}

TEST(Shading, LeavesAConstantFieldUnchanged) {
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 6, kBox, [](Vec3f) { return 0.7f; }, 0.2f),
                              "box");
  Renderer renderer(mesh, mesh.findField("f"), 16);
  renderer.setTransferFunction(opaqueAboveHalf());
  for (bool preintegrate : {false, true}) {
    const Frame plain = renderer.render(frontCamera(), frame(false, preintegrate));
    const Frame shaded = renderer.render(frontCamera(), frame(true, preintegrate));
    EXPECT_GT(brightness(plain.image, 0, plain.image.width), 0.0);
    EXPECT_EQ(plain.image.rgb, shaded.image.rgb) << "pre-integrated " << preintegrate;
  }
  EXPECT_EQ(renderer.gradientBytes(), mesh.points.size() * sizeof(Vec3f));
}

TEST(Shading, ChangesTheImageWhereTheGradientIsLarge) {
  // A ball: the field falls from 1 at the centre, and the function makes it opaque within radius 0.5.
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 14, kBox, [](Vec3f p) { return 1.f - length(p); }, 0.2f),
                              "ball");
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(opaqueAboveHalf());
  for (bool preintegrate : {false, true}) {
    const Frame plain = renderer.render(frontCamera(), frame(false, preintegrate));
    const Frame shaded = renderer.render(frontCamera(), frame(true, preintegrate));
    int changed = 0;
    for (size_t i = 0; i < plain.image.rgb.size(); ++i)
      changed += std::abs(int(plain.image.rgb[i]) - int(shaded.image.rgb[i])) > 8;
    EXPECT_GT(changed, int(plain.image.rgb.size() / 20)) << "pre-integrated " << preintegrate;
    // The background, where no ray meets the ball, stays as it was.
    EXPECT_EQ(shaded.image.pixel(0, 0)[0], plain.image.pixel(0, 0)[0]);
  }
}

TEST(Shading, TheSideFacingTheLightIsBrighter) {
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 14, kBox, [](Vec3f p) { return 1.f - length(p); }, 0.2f),
                              "ball");
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(opaqueAboveHalf());
  for (bool preintegrate : {false, true}) {
    RenderSettings settings = frame(true, preintegrate);
    settings.shading.headlight = false;
    for (float side : {1.f, -1.f}) {
      settings.shading.light = {side, 0.f, 1.f}; // camera space: from the right or the left
      const Image image = renderer.render(frontCamera(), settings).image;
      const int half = image.width / 2;
      const double right = brightness(image, half, image.width), left = brightness(image, 0, half);
      if (side > 0.f)
        EXPECT_GT(right, 1.1 * left) << "pre-integrated " << preintegrate;
      else
        EXPECT_GT(left, 1.1 * right) << "pre-integrated " << preintegrate;
    }
  }
}

TEST(Shading, FollowsANewField) {
  // setField recomputes the gradients: after a switch to a constant field, shading changes nothing.
  Mesh ball = buildMesh(makeBoxGrid(
                            CellType::Tetra, 8, kBox, [](Vec3f p) { return 1.f - length(p); }, 0.2f),
                        "ball");
  const Mesh flat = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 8, kBox, [](Vec3f) { return 0.7f; }, 0.2f),
                              "flat");
  Renderer renderer(ball, ball.findField("f"), 16);
  renderer.setTransferFunction(opaqueAboveHalf());
  const Frame lit = renderer.render(frontCamera(), frame(true, true));
  EXPECT_NE(lit.image.rgb, renderer.render(frontCamera(), frame(false, true)).image.rgb);
  renderer.setField(flat, flat.findField("f"));
  EXPECT_EQ(renderer.render(frontCamera(), frame(true, true)).image.rgb,
            renderer.render(frontCamera(), frame(false, true)).image.rgb);
}
