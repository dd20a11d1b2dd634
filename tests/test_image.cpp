// PNG input and output, SSIM and PSNR against scikit-image, and the sample heat map.
#include <uvr/error.h>
#include <uvr/image.h>

#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace uvr {
namespace {

namespace fs = std::filesystem;

/// A scratch directory per test, removed afterwards.
class ImageTest : public ::testing::Test {
protected:
  void SetUp() override {
    const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
    directory = fs::temp_directory_path() / ("uvr_test_image_" + std::string(info->name()));
    fs::create_directories(directory);
  }
  void TearDown() override { fs::remove_all(directory); }
  std::string path(const std::string &name) const { return (directory / name).string(); }

  fs::path directory;
};

/// The deterministic pair the skimage reference values below were computed for: a smooth-ish pattern,
/// `b` the same with small offsets, `d` a checkerboard of inverted and darkened blocks.
struct SyntheticImages {
  Image a, b, d;
};

SyntheticImages syntheticImages(int width, int height) {
  SyntheticImages images{Image(width, height), Image(width, height), Image(width, height)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int a = (x * 7 + y * 13 + c * 50 + (x * y) % 31) % 256;
        images.a.pixel(x, y)[c] = uint8_t(a);
        images.b.pixel(x, y)[c] = uint8_t(std::clamp(a + (x * 3 + y * 5 + c) % 17 - 8, 0, 255));
        images.d.pixel(x, y)[c] = uint8_t((x / 4 + y / 4) % 2 == 1 ? 255 - a : a / 2);
      }
  return images;
}

/// Writes a PNG of any colour type, bit depth and interlacing with libpng directly, to test the
/// conversions readPng makes. `rows` holds the packed rows as libpng expects them.
void writeRawPng(const std::string &path, int width, int height, int colorType, int bitDepth, bool interlaced,
                 const std::vector<uint8_t> &data, const std::vector<png_color> &palette = {}) {
  FILE *file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  const size_t rowBytes = data.size() / size_t(height);
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (int y = 0; y < height; ++y)
    rows[size_t(y)] = const_cast<uint8_t *>(data.data()) + size_t(y) * rowBytes;
  if (setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, file);
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), bitDepth, colorType,
                 interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    if (!palette.empty())
      png_set_PLTE(png, info, palette.data(), int(palette.size()));
    png_write_info(png, info);
    png_write_image(png, rows.data());
    png_write_end(png, info);
  } else {
    ADD_FAILURE() << "libpng failed writing " << path;
  }
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}

TEST_F(ImageTest, PngRoundTrip) {
  Image image(37, 23);
  for (size_t i = 0; i < image.rgb.size(); ++i)
    image.rgb[i] = uint8_t((i * 2654435761u) >> 24);
  writePng(path("round.png"), image);
  const Image read = readPng(path("round.png"));
  EXPECT_EQ(read.width, 37);
  EXPECT_EQ(read.height, 23);
  EXPECT_EQ(read.rgb, image.rgb);
}

TEST_F(ImageTest, ReadsGreyPaletteAlphaSixteenBitAndInterlaced) {
  const int width = 9, height = 5;
  std::vector<uint8_t> grey(size_t(width) * height), rgba, rgb16, indices;
  for (size_t i = 0; i < grey.size(); ++i) {
    grey[i] = uint8_t(i * 5);
    rgba.insert(rgba.end(), {uint8_t(i), uint8_t(2 * i), uint8_t(3 * i), uint8_t(100)});
    const uint16_t value = uint16_t(i * 1000); // big-endian, as PNG stores it
    for (int c = 0; c < 3; ++c)
      rgb16.insert(rgb16.end(), {uint8_t(value >> 8), uint8_t(value & 0xff)});
    indices.push_back(uint8_t(i % 3));
  }
  const std::vector<png_color> palette = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};

  writeRawPng(path("grey.png"), width, height, PNG_COLOR_TYPE_GRAY, 8, false, grey);
  writeRawPng(path("rgba.png"), width, height, PNG_COLOR_TYPE_RGB_ALPHA, 8, false, rgba);
  writeRawPng(path("rgb16.png"), width, height, PNG_COLOR_TYPE_RGB, 16, false, rgb16);
  writeRawPng(path("palette.png"), width, height, PNG_COLOR_TYPE_PALETTE, 8, false, indices, palette);
  writeRawPng(path("interlaced.png"), width, height, PNG_COLOR_TYPE_GRAY, 8, true, grey);

  const Image fromGrey = readPng(path("grey.png")), fromRgba = readPng(path("rgba.png"));
  const Image fromRgb16 = readPng(path("rgb16.png")), fromPalette = readPng(path("palette.png"));
  const Image fromInterlaced = readPng(path("interlaced.png"));
  for (const Image *image : {&fromGrey, &fromRgba, &fromRgb16, &fromPalette, &fromInterlaced}) {
    ASSERT_EQ(image->width, width);
    ASSERT_EQ(image->height, height);
  }
  for (size_t i = 0; i < grey.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(fromGrey.rgb[3 * i + c], grey[i]);
      EXPECT_EQ(fromInterlaced.rgb[3 * i + c], grey[i]);
      EXPECT_EQ(fromRgba.rgb[3 * i + c], rgba[4 * i + c]); // alpha is dropped, not composited
      EXPECT_EQ(fromRgb16.rgb[3 * i + c], uint8_t(std::lround(i * 1000 * 255.0 / 65535)));
      EXPECT_EQ(fromPalette.rgb[3 * i + c], c == int(i % 3) ? 255 : 0);
    }
}

TEST_F(ImageTest, BadPngsThrowErrors) {
  EXPECT_THROW(readPng(path("missing.png")), Error);

  std::ofstream(path("text.png")) << "not a png at all";
  EXPECT_THROW(readPng(path("text.png")), Error);

  Image image(64, 64);
  for (size_t i = 0; i < image.rgb.size(); ++i)
    image.rgb[i] = uint8_t(i * 7 + i / 191);
  writePng(path("whole.png"), image);
  std::ifstream in(path("whole.png"), std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  for (size_t length : {size_t(8), size_t(20), size_t(40), bytes.size() / 2, bytes.size() - 13}) {
    std::ofstream(path("truncated.png"), std::ios::binary) << bytes.substr(0, length);
    try {
      readPng(path("truncated.png"));
      ADD_FAILURE() << "reading a PNG truncated to " << length << " bytes did not throw";
    } catch (const Error &e) {
      EXPECT_NE(std::string(e.what()).find("truncated.png"), std::string::npos) << e.what();
    }
  }

  std::string corrupt = bytes;
  corrupt[bytes.size() / 2] = char(corrupt[bytes.size() / 2] ^ 0x5a);
  std::ofstream(path("corrupt.png"), std::ios::binary) << corrupt;
  EXPECT_THROW(readPng(path("corrupt.png")), Error);

  EXPECT_THROW(writePng(path("no/such/directory/out.png"), image), Error);
}

TEST(Ssim, IdenticalImagesGiveOneAndInfinitePsnr) {
  const SyntheticImages images = syntheticImages(40, 29);
  EXPECT_DOUBLE_EQ(ssim(images.a, images.a), 1.0);
  EXPECT_TRUE(std::isinf(psnr(images.a, images.a)));
}

TEST(Ssim, IsSymmetric) {
  const SyntheticImages images = syntheticImages(40, 29);
  EXPECT_NEAR(ssim(images.a, images.b), ssim(images.b, images.a), 1e-14);
  EXPECT_NEAR(ssim(images.a, images.d), ssim(images.d, images.a), 1e-14);
  EXPECT_DOUBLE_EQ(psnr(images.a, images.d), psnr(images.d, images.a));
}

// Reference values from scikit-image 0.19.3 for the same images, built with numpy as
//   y, x, c = np.mgrid[0:h, 0:w, 0:3]; a = (x*7 + y*13 + c*50 + (x*y) % 31) % 256
//   b = np.clip(a + (x*3 + y*5 + c) % 17 - 8, 0, 255); d = np.where((x//4 + y//4) % 2 == 1, 255 - a, a//2)
// (all as uint8), and
//   structural_similarity(a, b, channel_axis=2, gaussian_weights=True, sigma=1.5,
//                         use_sample_covariance=False, data_range=255)
//   peak_signal_noise_ratio(a, b, data_range=255)
TEST(Ssim, MatchesScikitImage) {
  const SyntheticImages large = syntheticImages(40, 29);
  EXPECT_NEAR(ssim(large.a, large.b), 0.98736555090660205, 1e-12);
  EXPECT_NEAR(ssim(large.a, large.d), -0.1409838206076707, 1e-12);
  EXPECT_NEAR(psnr(large.a, large.b), 34.392703236668382, 1e-10);
  EXPECT_NEAR(psnr(large.a, large.d), 6.805300535506758, 1e-10);

  // The smallest size skimage accepts: a single 11x11 window.
  const SyntheticImages small = syntheticImages(11, 11);
  EXPECT_NEAR(ssim(small.a, small.b), 0.98531546412432325, 1e-12);
  EXPECT_NEAR(ssim(small.a, small.d), -0.22367551970503599, 1e-12);
  EXPECT_NEAR(psnr(small.a, small.b), 34.389432668684975, 1e-10);
}

TEST(Ssim, RejectsDifferentAndTooSmallImages) {
  EXPECT_THROW(ssim(Image(20, 20), Image(20, 21)), Error);
  EXPECT_THROW(psnr(Image(20, 20), Image(21, 20)), Error);
  EXPECT_THROW(ssim(Image(10, 40), Image(10, 40)), Error);
  EXPECT_THROW(ssim(Image(), Image()), Error);
}

/// A radial ramp of sample counts from `low` in the corners up to `high` in the centre.
std::vector<uint32_t> radialSamples(int width, int height, uint32_t low, uint32_t high) {
  std::vector<uint32_t> samples(size_t(width) * size_t(height));
  const double maxRadius = std::hypot(width / 2.0, height / 2.0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double r = std::hypot(x + 0.5 - width / 2.0, y + 0.5 - height / 2.0) / maxRadius;
      samples[size_t(y) * size_t(width) + size_t(x)] = low + uint32_t(std::lround((1 - r) * (high - low)));
    }
  return samples;
}

size_t countWhite(const Image &image, int x0, int x1) {
  size_t count = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = x0; x < x1; ++x) {
      const uint8_t *p = image.pixel(x, y);
      count += p[0] == 255 && p[1] == 255 && p[2] == 255;
    }
  return count;
}

TEST(Heatmap, ColourCodesAndDrawsTheScale) {
  for (int size : {64, 256, 1024}) {
    const Image image = heatmapImage(radialSamples(size, size, 10, 5000), size, size);
    ASSERT_EQ(image.width, size);
    ASSERT_EQ(image.height, size);
    // The colour map never reaches pure white; the bar's labels and ticks are white, at the right edge only.
    EXPECT_GT(countWhite(image, size / 2, size), size_t(20)) << size;
    EXPECT_EQ(countWhite(image, 0, size / 3), size_t(0)) << size;
    // The bar's top has the map's top colour (light yellow), which the data here never reach at the right.
    bool light = false;
    for (int y = 0; y < size; ++y) {
      const uint8_t *p = image.pixel(size - 1 - std::max(1, size / 200) * 6, y);
      light |= p[0] > 240 && p[1] > 240 && p[2] > 140 && p[2] < 200;
    }
    EXPECT_TRUE(light) << size;
  }
}

TEST(Heatmap, TheBarsBlackEndIsFramedAndTheTitleSaysSamplesPerPixel) {
  // All-zero counts but one: the image is the map's black end, where a black outline would vanish.
  std::vector<uint32_t> samples(size_t(256) * 256, 0);
  samples[0] = 100;
  const Image image = heatmapImage(samples, 256, 256);
  size_t grey = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = image.width / 2; x < image.width; ++x) {
      const uint8_t *p = image.pixel(x, y);
      grey += p[0] == 160 && p[1] == 160 && p[2] == 160;
    }
  EXPECT_GT(grey, size_t(2 * 128)) << "the bar's frame runs down both its sides";
  // "samples per pixel" is three words wide: white text spans far more than "samples" (41 pixels) would.
  int left = image.width;
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < image.width; ++x) {
      const uint8_t *p = image.pixel(x, y);
      if (p[0] == 255 && p[1] == 255 && p[2] == 255)
        left = std::min(left, x);
    }
  EXPECT_LT(left, image.width - 4 - 1 - 90);
}

TEST(Heatmap, SmallImagesAreStillColourCoded) {
  const Image image = heatmapImage({0, 1, 2, 3, 4, 5, 6, 7, 8}, 3, 3);
  ASSERT_EQ(image.width, 3);
  EXPECT_EQ(countWhite(image, 0, 3), size_t(0));
  EXPECT_LT(image.pixel(0, 0)[0], 10);  // minimum: black
  EXPECT_GT(image.pixel(2, 2)[1], 240); // maximum: light yellow
  EXPECT_LT(image.pixel(0, 1)[0], image.pixel(2, 1)[0]);

  const Image flat = heatmapImage(std::vector<uint32_t>(100 * 100, 7), 100, 100);
  EXPECT_EQ(flat.width, 100);
  EXPECT_THROW(heatmapImage({1, 2, 3}, 2, 2), Error);
}

} // namespace
} // namespace uvr
