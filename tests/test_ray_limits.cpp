// FrameSettings::rayLimits: each pixel's ray ends at its limit, as where opaque geometry of another renderer
// hides the volume.
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace uvr {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// A unit cube of one hexahedron, its field growing along x.
VolumeMesh cube() {
  const std::vector<float> points{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  const std::vector<float> values{0, 1, 1, 0, 0, 1, 1, 0};
  const std::vector<int64_t> offsets{0, 8}, connectivity{0, 1, 2, 3, 4, 5, 6, 7};
  const std::vector<uint8_t> types{12};
  MeshArrays arrays;
  arrays.points = ArrayView(std::span<const float>(points), 3);
  arrays.offsets = offsets;
  arrays.connectivity = connectivity;
  arrays.types = types;
  arrays.fields.push_back({"f", Centering::Point, ArrayView(std::span<const float>(values))});
  return VolumeMesh::fromArrays(arrays);
}

constexpr int kSize = 16;
const Camera kCamera{{0.5f, 0.5f, 4.f}, {0.5f, 0.5f, 0.5f}, {0.f, 1.f, 0.f}, 20.f};

class RayLimits : public testing::TestWithParam<RenderMode> {};

TEST_P(RayLimits, EndEachRayAtItsLimit) {
  VolumeRenderer renderer(cube(), 0);
  renderer.setTransferFunction(builtinColorMap("viridis"), {0.f, 1.f});
  FrameSettings settings;
  settings.mode = GetParam();
  settings.width = settings.height = kSize;
  settings.s1 = 0.01f;
  settings.unit = 0.5f;
  const FrameResult open = renderer.render(kCamera, settings);
  const size_t centre = size_t(kSize / 2) * kSize + kSize / 2;
  ASSERT_GT(open.opacity[centre], 0.1f);

  std::vector<float> limits(size_t(kSize) * kSize, kInf);
  settings.rayLimits = limits;
  const FrameResult unlimited = renderer.render(kCamera, settings);
  EXPECT_EQ(unlimited.image.rgb, open.image.rgb);
  EXPECT_EQ(unlimited.opacity, open.opacity);

  // Half way through the cube along the central rays: less opacity there, and none anywhere more.
  std::fill(limits.begin(), limits.end(), 3.5f);
  const FrameResult half = renderer.render(kCamera, settings);
  EXPECT_GT(half.opacity[centre], 0.05f);
  EXPECT_LT(half.opacity[centre], open.opacity[centre] - 0.05f);
  for (size_t i = 0; i < limits.size(); ++i)
    EXPECT_LE(half.opacity[i], open.opacity[i] + 1e-6f) << i;

  // Ending before the cube: nothing drawn.
  std::fill(limits.begin(), limits.end(), 2.f);
  const FrameResult none = renderer.render(kCamera, settings);
  for (const float opacity : none.opacity)
    EXPECT_EQ(opacity, 0.f);
}

INSTANTIATE_TEST_SUITE_P(Modes, RayLimits,
                         testing::Values(RenderMode::Reference, RenderMode::Skip, RenderMode::Adaptive,
                                         RenderMode::Full),
                         [](const testing::TestParamInfo<RenderMode> &info) { return modeName(info.param); });

TEST(RayLimitsCheck, RefusesAWrongCountOrNegativeLimits) {
  const auto refusal = [](const FrameSettings &s) {
    try {
      validateSettings(s);
    } catch (const Error &e) {
      return std::string(e.what());
    }
    return std::string();
  };
  FrameSettings s;
  s.width = s.height = 4;
  std::vector<float> limits(15, 1.f);
  s.rayLimits = limits;
  EXPECT_NE(refusal(s).find("rayLimits"), std::string::npos);
  limits.assign(16, 1.f);
  s.rayLimits = limits;
  EXPECT_EQ(refusal(s), "");
  for (const float bad : {-1.f, std::numeric_limits<float>::quiet_NaN()}) {
    limits[5] = bad;
    EXPECT_NE(refusal(s).find("rayLimits"), std::string::npos) << bad;
  }
}

} // namespace
} // namespace uvr
