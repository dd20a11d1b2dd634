// The library's checks that every front end relies on: camera and settings validation, named views, the
// default opacity unit distance and the default transfer-function range.
#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>
#include <uvr/system.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace uvr {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

std::string refusal(const Camera &camera) {
  try {
    validateCamera(camera);
  } catch (const Error &e) {
    return e.what();
  }
  return {};
}

TEST(ValidateCamera, RefusesDegenerateCamerasNamingTheField) {
  const Camera good{{0.f, 0.f, 5.f}, {0.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, 30.f};
  EXPECT_NO_THROW(validateCamera(good));
  for (const float fovy : {0.f, -1.f, 180.f, 200.f, kNan, kInf}) {
    Camera c = good;
    c.fovy = fovy;
    EXPECT_NE(refusal(c).find("fovy"), std::string::npos) << fovy;
  }
  Camera c = good;
  c.eye = c.at;
  EXPECT_NE(refusal(c).find("eye"), std::string::npos);
  c = good;
  c.eye.x = kNan;
  EXPECT_NE(refusal(c).find("eye"), std::string::npos);
  c = good;
  c.at.y = kInf;
  EXPECT_NE(refusal(c).find("at"), std::string::npos);
  c = good;
  c.up = {0.f, 0.f, 0.f};
  EXPECT_NE(refusal(c).find("up"), std::string::npos);
  c = good;
  c.up = {0.f, 0.f, -2.f}; // parallel to the view direction
  EXPECT_NE(refusal(c).find("parallel"), std::string::npos);
  c = good;
  c.up = {0.f, kNan, 0.f};
  EXPECT_NE(refusal(c).find("up"), std::string::npos);
  // Finite, but the view direction overflows, or its length does: said so, not called parallel to up.
  c = good;
  c.eye = {3.f, 3.f, 3e38f};
  c.at = {3.f, 3.f, -3e38f};
  EXPECT_NE(refusal(c).find("too far apart"), std::string::npos) << refusal(c);
  c.at = {3.f, 3.f, 0.f};
  EXPECT_NO_THROW(validateCamera(c));
}

// From an eye so far that float positions along the rays cannot resolve the step, a frame is refused, never
// left marching in place.
TEST(Renderer, RefusesACameraTooFarForTheStep) {
  const std::vector<float> points{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, values{0, 1, 2, 3};
  const std::vector<int64_t> offsets{0, 4}, connectivity{0, 1, 2, 3};
  const std::vector<uint8_t> types{10};
  MeshArrays arrays;
  arrays.points = ArrayView(std::span<const float>(points), 3);
  arrays.offsets = offsets;
  arrays.connectivity = connectivity;
  arrays.types = types;
  arrays.fields.push_back({"f", Centering::Point, ArrayView(std::span<const float>(values))});
  VolumeRenderer renderer(VolumeMesh::fromArrays(arrays), 0);
  renderer.setTransferFunction(builtinColorMap("viridis"), {0.f, 3.f});
  FrameSettings settings;
  settings.width = settings.height = 8;
  Camera camera{{0.3f, 0.3f, 1e30f}, {0.3f, 0.3f, 0.f}, {0.f, 1.f, 0.f}, 30.f};
  try {
    renderer.render(camera, settings);
    ADD_FAILURE() << "no uvr::Error";
  } catch (const Error &e) {
    EXPECT_NE(std::string(e.what()).find("too far"), std::string::npos) << e.what();
  }
  camera.eye.z = 1e3f;
  EXPECT_NO_THROW(renderer.render(camera, settings));
}

TEST(NamedViews, FrameTheBoundsFromEachSide) {
  Box3f box;
  box.extend(Vec3f{-1.f, -2.f, -3.f});
  box.extend(Vec3f{1.f, 2.f, 3.f});
  const Camera reset = frameBounds(box);
  const float distance = length(reset.eye - reset.at);
  ASSERT_EQ(cameraViewNames(), (std::vector<std::string>{"+x", "-x", "+y", "-y", "+z", "-z", "iso"}));
  for (const std::string &name : cameraViewNames()) {
    const Camera c = frameBounds(box, name);
    EXPECT_NEAR(length(c.eye - c.at), distance, 1e-4f * distance) << name;
    const Vec3f from = normalize(c.eye - c.at);
    const float sign = name[0] == '-' ? -1.f : 1.f;
    const int axis = name == "iso" ? -1 : name[1] - 'x';
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(from[a], axis < 0 ? 1.f / std::sqrt(3.f) : (a == axis ? sign : 0.f), 1e-6f) << name;
    EXPECT_NO_THROW(validateCamera(c)) << name;
  }
  const Camera plusZ = frameBounds(box, "+z");
  EXPECT_EQ(plusZ.eye.z, reset.eye.z); // the reset camera itself
  EXPECT_THROW(frameBounds(box, "x"), Error);
  EXPECT_THROW(frameBounds(box, "+z", 0.f), Error);
}

TEST(ValidateSettings, RefusesNegativeNonFiniteAndOutOfRange) {
  EXPECT_NO_THROW(validateSettings(FrameSettings{})); // zeros: the defaults
  const auto refused = [](FrameSettings s, const char *name) {
    try {
      validateSettings(s);
    } catch (const Error &e) {
      return std::string(e.what()).find(name) != std::string::npos;
    }
    return false;
  };
  for (const float bad : {-1.f, kNan, kInf}) {
    FrameSettings s;
    s.s1 = bad;
    EXPECT_TRUE(refused(s, "s1"));
    s = {};
    s.unit = bad;
    EXPECT_TRUE(refused(s, "unit"));
    s = {};
    s.background.y = bad;
    EXPECT_TRUE(refused(s, "background"));
  }
  FrameSettings s;
  s.p = 0.5f;
  EXPECT_TRUE(refused(s, "p"));
  s = {};
  s.s1 = 2.f;
  s.s2 = 1.f;
  EXPECT_TRUE(refused(s, "s2"));
  s = {};
  s.background = {1.f, 1.f, 255.f};
  EXPECT_TRUE(refused(s, "background"));
  s = {};
  s.width = 0;
  EXPECT_TRUE(refused(s, "size"));
}

TEST(DefaultUnitDistance, IsTheDiagonalOverTheCubeRootOfTheCells) {
  // A 20 m wind tunnel of a million cells: units of centimetres, whatever the cells near a wall measure.
  Box3f tunnel;
  tunnel.extend(Vec3f{0.f, 0.f, 0.f});
  tunnel.extend(Vec3f{20.f, 4.f, 4.f});
  EXPECT_NEAR(defaultUnitDistance(tunnel, 1000000), std::sqrt(432.f) / 100.f, 1e-5f);
  EXPECT_EQ(defaultUnitDistance(Box3f{}, 0), 1.f);
  const FrameSettings filled = withDefaultSampling({}, 0.01f, 0.2f);
  EXPECT_EQ(filled.s1, 0.01f);
  EXPECT_EQ(filled.unit, 0.2f);
  FrameSettings explicitUnit;
  explicitUnit.unit = 3.f;
  EXPECT_EQ(withDefaultSampling(explicitUnit, 0.01f, 0.2f).unit, 3.f);
}

TEST(DefaultTransferRange, WidensAConstantField) {
  EXPECT_EQ(defaultTransferRange({1.f, 2.f}).min, 1.f);
  const ValueRange constant = defaultTransferRange({5.f, 5.f});
  EXPECT_LT(constant.min, 5.f);
  EXPECT_GT(constant.max, 5.f);
  EXPECT_FLOAT_EQ(0.5f * (constant.min + constant.max), 5.f);
  const ValueRange large = defaultTransferRange({1e9f, 1e9f});
  EXPECT_LT(large.min, large.max); // wide enough to survive float rounding
}

TEST(SetThreadCount, LimitsTheLoopsAndLiftsTheLimit) {
  const int all = threadCount();
  setThreadCount(1);
  EXPECT_EQ(threadCount(), 1);
  setThreadCount(0);
  EXPECT_EQ(threadCount(), all);
  EXPECT_THROW(setThreadCount(-1), Error);
  EXPECT_EQ(threadCount(), all);
}

} // namespace
} // namespace uvr
