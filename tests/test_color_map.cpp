// Transfer-function presets: ParaView's JSON, the built-in maps, and sampling as VTK samples them. The
// reference values marked "VTK" were computed with VTK 9.1's vtkColorTransferFunction / vtkPiecewiseFunction.
#include "core/color_map.h"

#include <uvr/error.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace uvr {
namespace {

const std::string kPresets = std::string(UVR_TEST_DATA) + "/presets/";

void expectColor(const Vec4f &sample, float r, float g, float b, float tolerance = 1e-5f) {
  EXPECT_NEAR(sample.x, r, tolerance);
  EXPECT_NEAR(sample.y, g, tolerance);
  EXPECT_NEAR(sample.z, b, tolerance);
}

ColorMap makeMap(std::vector<float> rgbPoints, std::vector<float> opacityPoints = {},
                 std::string colorSpace = "RGB") {
  ColorMap map;
  map.name = "test";
  map.rgbPoints = std::move(rgbPoints);
  map.opacityPoints = std::move(opacityPoints);
  map.colorSpace = std::move(colorSpace);
  return map;
}

// --- Reading ParaView's JSON ---

TEST(ColorMapFile, TakesFirstPresetWithRGBPoints) {
  // The first entry is categorical (IndexedColors only) and is skipped.
  const ColorMap map = readColorMapFile(kPresets + "two_presets.json");
  EXPECT_EQ(map.name, "Ramp with Points (test)");
  EXPECT_EQ(map.colorSpace, "RGB");
  ASSERT_EQ(map.rgbPoints.size(), 12u);
  EXPECT_FLOAT_EQ(map.rgbPoints[4], 20.f);
  EXPECT_FLOAT_EQ(map.rgbPoints[6], 0.5f);
  ASSERT_EQ(map.opacityPoints.size(), 16u);
  EXPECT_FLOAT_EQ(map.opacityPoints[6], 0.25f); // midpoint of the second point
  EXPECT_FLOAT_EQ(map.opacityPoints[11], 1.f);  // sharpness of the third
  EXPECT_FLOAT_EQ(map.nanColor.x, 0.25f);
  EXPECT_FLOAT_EQ(map.nanColor.z, 0.5f);
}

TEST(ColorMapFile, TakesPresetByName) {
  const ColorMap map = readColorMapFile(kPresets + "two_presets.json", "Blue to Red HSV (test)");
  EXPECT_EQ(map.name, "Blue to Red HSV (test)");
  EXPECT_EQ(map.colorSpace, "HSV");
  EXPECT_TRUE(map.opacityPoints.empty());
  EXPECT_EQ(map.rgbPoints.size(), 8u);
  EXPECT_EQ(readColorMapFile(kPresets + "two_presets.json", "blue to red hsv (TEST)").name,
            "Blue to Red HSV (test)");
}

TEST(ColorMapFile, ReadsParaViewExportOfCoolToWarm) {
  const ColorMap file = readColorMapFile(kPresets + "cool_to_warm.json");
  const ColorMap builtin = builtinColorMap("Cool to Warm");
  EXPECT_EQ(file.name, builtin.name);
  EXPECT_EQ(file.colorSpace, builtin.colorSpace);
  EXPECT_EQ(file.rgbPoints, builtin.rgbPoints);
  EXPECT_EQ(file.opacityPoints, builtin.opacityPoints);
}

TEST(ColorMapFile, ListsPresetsWithRGBPoints) {
  const std::vector<ColorMap> maps = readColorMapPresets(kPresets + "two_presets.json");
  ASSERT_EQ(maps.size(), 2u); // the first preset is indexed colours only
  EXPECT_EQ(maps[0].name, "Ramp with Points (test)");
  EXPECT_EQ(maps[1].name, "Blue to Red HSV (test)");
}

TEST(ColorMapFile, WrittenPresetReadsBack) {
  ColorMap map = readColorMapFile(kPresets + "two_presets.json", "Ramp with Points (test)");
  map.name = "Edited";
  map.opacityPoints = {0.f, 0.f, 0.5f, 0.f, 25.f, 0.75f, 0.25f, 1.f, 40.f, 0.1f, 0.5f, 0.f};
  const std::string path = (std::filesystem::temp_directory_path() / "uvr_written_preset.json").string();
  writeColorMapFile(path, map);
  const ColorMap back = readColorMapFile(path, "Edited");
  std::filesystem::remove(path);
  EXPECT_EQ(back.rgbPoints, map.rgbPoints);
  EXPECT_EQ(back.opacityPoints, map.opacityPoints);
  EXPECT_EQ(back.colorSpace, map.colorSpace);
  EXPECT_EQ(back.nanColor.x, map.nanColor.x);
  EXPECT_EQ(back.nanColor.z, map.nanColor.z);
  EXPECT_THROW(writeColorMapFile("/nonexistent-dir/x.json", map), Error);
}

TEST(ColorMapFile, ShippedBrainPresetsRead) {
  const std::string path = std::string(UVR_TEST_DATA) + "/../../data/presets/brain.json";
  for (const char *name : {"Brain Binary", "Brain Translucent"}) {
    const ColorMap map = readColorMapFile(path, name);
    EXPECT_FALSE(map.opacityPoints.empty()) << name;
    EXPECT_FLOAT_EQ(map.rgbPoints[map.rgbPoints.size() - 4], 125.f) << name;
  }
  // Binary: nothing below the white matter shows, the white matter is opaque.
  const std::vector<Vec4f> binary = sampleColorMap(readColorMapFile(path, "Brain Binary"), 126);
  EXPECT_EQ(binary[60].w, 0.f);
  EXPECT_GT(binary[100].w, 0.9f);
}

// Malformed files, each written to a scratch directory; every error names the file.
class ColorMapFileErrors : public ::testing::Test {
protected:
  void SetUp() override {
    directory_ =
        std::filesystem::temp_directory_path() /
        ("uvr_color_map_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::string write(const std::string &text) {
    const std::string path = (directory_ / "preset.json").string();
    std::ofstream(path) << text;
    return path;
  }

  // The message of the uvr::Error that reading `text` throws; checks that it names the file.
  std::string errorFor(const std::string &text, const std::string &name = {}) {
    const std::string path = write(text);
    try {
      readColorMapFile(path, name);
    } catch (const Error &e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      return message;
    }
    ADD_FAILURE() << "no error for " << text;
    return {};
  }

  std::filesystem::path directory_;
};

constexpr const char *kGood = R"("Name": "A", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1])";

TEST_F(ColorMapFileErrors, AcceptsSingleObject) {
  const ColorMap map = readColorMapFile(write(std::string("{") + kGood + "}"));
  EXPECT_EQ(map.name, "A");
  EXPECT_EQ(map.colorSpace, "RGB");
}

TEST_F(ColorMapFileErrors, SyntaxErrorGivesByteOffset) {
  const std::string message = errorFor("[{\"Name\": \"A\", \"RGBPoints\": [0, 0, 0, 0,, 1]}]");
  EXPECT_NE(message.find("byte 40"), std::string::npos) << message;
}

TEST_F(ColorMapFileErrors, MissingRGBPoints) {
  EXPECT_NE(errorFor(R"([{"Name": "A", "Points": [0, 0, 0.5, 0]}])").find("RGBPoints"), std::string::npos);
  EXPECT_NE(errorFor(R"([{"Name": "A"}])", "A").find("no RGBPoints"), std::string::npos);
}

TEST_F(ColorMapFileErrors, RGBPointsNotWhole) {
  const std::string message = errorFor(R"([{"Name": "A", "RGBPoints": [0, 0, 0, 0, 1, 1, 1]}])");
  EXPECT_NE(message.find("multiple of 4"), std::string::npos) << message;
  EXPECT_NE(message.find("preset \"A\""), std::string::npos) << message;
}

TEST_F(ColorMapFileErrors, OpacityPointsNotWhole) {
  const std::string message = errorFor(std::string("[{") + kGood + R"(, "Points": [0, 0, 0.5, 0, 1, 1]}])");
  EXPECT_NE(message.find("Points has 6 values"), std::string::npos) << message;
}

TEST_F(ColorMapFileErrors, DecreasingX) {
  EXPECT_NE(errorFor(R"([{"Name": "A", "RGBPoints": [1, 0, 0, 0, 0, 1, 1, 1]}])").find("must not decrease"),
            std::string::npos);
  EXPECT_NE(errorFor(std::string("[{") + kGood + R"(, "Points": [1, 0, 0.5, 0, 0, 1, 0.5, 0]}])")
                .find("Points x values must not decrease"),
            std::string::npos);
}

TEST_F(ColorMapFileErrors, NoPresetOfThatName) {
  const std::string message =
      errorFor(std::string("[{") + kGood + R"(}, {"Name": "B", "RGBPoints": [0, 1, 1, 1]}])", "C");
  EXPECT_NE(message.find("no preset named \"C\""), std::string::npos) << message;
  EXPECT_NE(message.find("\"A\", \"B\""), std::string::npos) << message;
}

TEST_F(ColorMapFileErrors, UnknownColorSpace) {
  const std::string message = errorFor(std::string("[{") + kGood + R"(, "ColorSpace": "Rainbow"}])");
  EXPECT_NE(message.find("unknown ColorSpace \"Rainbow\""), std::string::npos) << message;
}

TEST_F(ColorMapFileErrors, NotNumbersOrNoFile) {
  EXPECT_NE(
      errorFor(R"([{"Name": "A", "RGBPoints": [0, "red", 0, 0]}])").find("RGBPoints[1] is not a number"),
      std::string::npos);
  EXPECT_THROW(readColorMapFile((directory_ / "missing.json").string()), Error);
}

// --- Sampling ---

TEST(SampleColorMap, RGBExactAtAndBetweenPoints) {
  // Range [10, 40] in steps of 0.5: sample i is at x = 10 + i / 2.
  const std::vector<Vec4f> samples = sampleColorMap(readColorMapFile(kPresets + "two_presets.json"), 61);
  ASSERT_EQ(samples.size(), 61u);
  expectColor(samples[0], 0.f, 0.f, 0.f);
  expectColor(samples[10], 0.5f, 0.25f, 0.f); // x = 15
  expectColor(samples[20], 1.f, 0.5f, 0.f);   // x = 20, a control point
  expectColor(samples[40], 1.f, 0.75f, 0.5f); // x = 30
  expectColor(samples[60], 1.f, 1.f, 1.f);
}

TEST(SampleColorMap, OpacityMidpointAndSharpness) {
  const std::vector<Vec4f> samples = sampleColorMap(readColorMapFile(kPresets + "two_presets.json"), 61);
  // 10 -> 20, midpoint 0.5, sharpness 0: linear.
  EXPECT_NEAR(samples[5].w, 0.1f, 1e-6f);
  EXPECT_NEAR(samples[10].w, 0.2f, 1e-6f);
  EXPECT_NEAR(samples[20].w, 0.4f, 1e-6f);
  // 20 -> 30, midpoint 0.25: halfway (0.5) a quarter of the way along, at x = 22.5; then linear to 0.6.
  EXPECT_NEAR(samples[25].w, 0.5f, 1e-6f);
  EXPECT_NEAR(samples[30].w, 0.5f + 0.1f * (2.5f / 7.5f), 1e-6f);
  // 30 -> 40, sharpness 1: a step at the midpoint, x = 35.
  EXPECT_NEAR(samples[40].w, 0.6f, 1e-6f);
  EXPECT_NEAR(samples[49].w, 0.6f, 1e-6f);
  EXPECT_NEAR(samples[50].w, 1.f, 1e-6f);
  EXPECT_NEAR(samples[60].w, 1.f, 1e-6f);
}

TEST(SampleColorMap, OpacityHermiteCurveMatchesVTK) {
  // Sharpness 0.5 between 0 and 1: an S curve through 0.5 at the midpoint.
  const std::vector<Vec4f> samples =
      sampleColorMap(makeMap({0, 0, 0, 0, 1, 1, 1, 1}, {0, 0, 0.5f, 0.5f, 1, 1, 0.5f, 0}), 21);
  EXPECT_NEAR(samples[5].w, 0.0039973259f, 1e-6f); // VTK
  EXPECT_NEAR(samples[8].w, 0.0890540040f, 1e-6f); // VTK
  EXPECT_NEAR(samples[10].w, 0.5f, 1e-6f);
  EXPECT_NEAR(samples[15].w, 0.9960026741f, 1e-6f); // VTK
  for (int i = 1; i < 21; ++i)
    EXPECT_GE(samples[i].w, samples[i - 1].w);
}

TEST(SampleColorMap, DivergingCoolToWarm) {
  const std::vector<Vec4f> samples = sampleColorMap(builtinColorMap("Cool to Warm"), 5);
  expectColor(samples[0], 0.23137255f, 0.29803923f, 0.75294119f);
  expectColor(samples[1], 0.55352428f, 0.68840739f, 0.99491511f, 1e-4f); // VTK
  expectColor(samples[2], 0.865f, 0.865f, 0.865f, 1e-4f);
  expectColor(samples[3], 0.95827876f, 0.60292092f, 0.48172695f, 1e-4f); // VTK
  // At a control point Diverging still round-trips through L*a*b*, which VTK's rounded matrices blur
  // slightly.
  expectColor(samples[4], 0.70588235f, 0.01568627f, 0.14901961f, 2e-4f);
  // Its opacity ramp.
  EXPECT_FLOAT_EQ(samples[0].w, 0.f);
  EXPECT_FLOAT_EQ(samples[2].w, 0.5f);
  EXPECT_FLOAT_EQ(samples[4].w, 1.f);
}

TEST(SampleColorMap, DivergingInsertsWhiteBetweenDistinctHues) {
  const std::vector<Vec4f> samples = sampleColorMap(makeMap({0, 0, 0, 1, 1, 1, 0, 0}, {}, "Diverging"), 5);
  expectColor(samples[1], 0.73781580f, 0.59858211f, 1.f, 1e-4f); // VTK
  expectColor(samples[2], 1.f, 1.f, 1.f, 1e-4f);
}

TEST(SampleColorMap, HSVTakesShorterHuePath) {
  // Blue (hue 2/3) to red (hue 0 = 1) goes through magenta, not green.
  const std::vector<Vec4f> samples =
      sampleColorMap(readColorMapFile(kPresets + "two_presets.json", "Blue to Red HSV (test)"), 5);
  expectColor(samples[1], 0.5f, 0.f, 1.f); // VTK
  expectColor(samples[2], 1.f, 0.f, 1.f);  // VTK
  expectColor(samples[3], 1.f, 0.f, 0.5f); // VTK
}

TEST(SampleColorMap, LabAndStep) {
  expectColor(sampleColorMap(makeMap({0, 0, 0, 1, 1, 1, 1, 0}, {}, "Lab"), 3)[1], 0.79127808f, 0.54260090f,
              0.66546586f, 1e-4f); // VTK
  // Step: each point's colour holds back to the previous point.
  const std::vector<Vec4f> step =
      sampleColorMap(makeMap({0, 1, 0, 0, 0.3f, 0, 1, 0, 1, 0, 0, 1}, {}, "Step"), 11);
  expectColor(step[0], 1.f, 0.f, 0.f);
  expectColor(step[2], 0.f, 1.f, 0.f);
  expectColor(step[3], 0.f, 1.f, 0.f);
  expectColor(step[4], 0.f, 0.f, 1.f);
  expectColor(step[10], 0.f, 0.f, 1.f);
}

TEST(SampleColorMap, DefaultOpacityRampAndRangeUnion) {
  // No opacity points: a linear ramp from 0 to 1 over the colour range.
  const std::vector<Vec4f> ramp = sampleColorMap(makeMap({2, 0, 0, 0, 4, 1, 1, 1}), 3);
  EXPECT_FLOAT_EQ(ramp[0].w, 0.f);
  EXPECT_FLOAT_EQ(ramp[1].w, 0.5f);
  EXPECT_FLOAT_EQ(ramp[2].w, 1.f);
  // Opacity points beyond the colour points widen the sampled range; colours hold their end values there.
  const std::vector<Vec4f> wide =
      sampleColorMap(makeMap({2, 0, 0, 0, 4, 1, 1, 1}, {0, 0, 0.5f, 0, 8, 1, 0.5f, 0}), 9);
  expectColor(wide[0], 0.f, 0.f, 0.f);
  expectColor(wide[3], 0.5f, 0.5f, 0.5f);
  expectColor(wide[8], 1.f, 1.f, 1.f);
  EXPECT_FLOAT_EQ(wide[4].w, 0.5f);
}

TEST(SampleColorMap, CountsAndInvalidMaps) {
  EXPECT_TRUE(sampleColorMap(builtinColorMap("grayscale"), 0).empty());
  const std::vector<Vec4f> one = sampleColorMap(builtinColorMap("grayscale"), 1);
  ASSERT_EQ(one.size(), 1u);
  expectColor(one[0], 0.5f, 0.5f, 0.5f);
  EXPECT_THROW(sampleColorMap(makeMap({}), 4), Error);
  EXPECT_THROW(sampleColorMap(makeMap({0, 0, 0, 0}, {}, "CMYK"), 4), Error);
}

// --- Built-in presets ---

TEST(BuiltinColorMaps, NamesResolve) {
  const std::vector<std::string> names = builtinColorMapNames();
  ASSERT_GE(names.size(), 4u);
  EXPECT_EQ(names.front(), "Cool to Warm");
  EXPECT_FALSE(builtinColorMap(names.front()).opacityPoints.empty());
  for (const std::string &name : names) {
    const ColorMap map = builtinColorMap(name);
    EXPECT_EQ(map.name, name);
    EXPECT_NO_THROW(sampleColorMap(map, 16)) << name;
  }
  EXPECT_EQ(builtinColorMap("viridis").name, "Viridis (matplotlib)");
  EXPECT_EQ(builtinColorMap("VIRIDIS (MATPLOTLIB)").name, "Viridis (matplotlib)");
  EXPECT_EQ(builtinColorMap("inferno").name, "Inferno (matplotlib)");
  EXPECT_EQ(builtinColorMap("cool-to-warm").name, "Cool to Warm");
  EXPECT_EQ(builtinColorMap("Grayscale").name, "Grayscale");
  EXPECT_THROW(builtinColorMap("jet"), Error);
}

TEST(BuiltinColorMaps, ViridisFollowsMatplotlib) {
  const ColorMap viridis = builtinColorMap("viridis");
  EXPECT_GE(viridis.rgbPoints.size() / 4, 32u);
  // matplotlib's _viridis_data[0], [255] and between [127] and [128].
  const std::vector<Vec4f> samples = sampleColorMap(viridis, 3);
  expectColor(samples[0], 0.267004f, 0.004874f, 0.329415f, 1e-4f);
  expectColor(samples[1], 0.128149f, 0.565107f, 0.550893f, 2e-3f);
  expectColor(samples[2], 0.993248f, 0.906157f, 0.143936f, 1e-4f);
  const std::vector<Vec4f> inferno = sampleColorMap(builtinColorMap("inferno"), 2);
  expectColor(inferno[1], 0.988362f, 0.998364f, 0.644924f, 1e-4f);
}

} // namespace
} // namespace uvr
