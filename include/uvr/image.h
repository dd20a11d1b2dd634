// 8-bit RGB images: what the renderer draws; PNG files, image comparison (SSIM, PSNR) and heat maps.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace uvr {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb; ///< row-major, top row first, 3 bytes per pixel

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3, 0) {}
  uint8_t *pixel(int x, int y) { return &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
  const uint8_t *pixel(int x, int y) const { return &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
};

/// Writes an 8-bit RGB PNG; throws uvr::Error on failure.
void writePng(const std::string &path, const Image &image);

/// Reads any PNG (grey, palette, alpha and 16-bit are converted; alpha is dropped) as 8-bit RGB.
Image readPng(const std::string &path);

/// Structural similarity over the RGB channels, as scikit-image's
/// structural_similarity(channel_axis=2, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
/// data_range=255) computes it: Gaussian window sigma 1.5 truncated at 3.5 sigma (11x11), K1 = 0.01,
/// K2 = 0.03, mean over the valid interior of each channel, then over channels.
double ssim(const Image &a, const Image &b);

/// Peak signal-to-noise ratio in dB over all channels (infinity for identical images).
double psnr(const Image &a, const Image &b);

/// Colour-codes samples per pixel (row-major, top row first) with a perceptual colour map and draws the
/// scale (a colour bar with its minimum and maximum labelled) into the image, as the paper's heat maps.
Image heatmapImage(const std::vector<uint32_t> &samplesPerPixel, int width, int height);

} // namespace uvr
