// Where a ray's result goes: the frame's buffers as plain pointers, written the same way by every backend.
#pragma once

#include "core/host_device.h"
#include "render/integrator.h"

#include <cstdint>

namespace uvr {

/// The samples a frame took, summed over its pixels, and the most any pixel took.
struct SampleTotals {
  unsigned long long total = 0;
  uint32_t max = 0;
};

struct PixelTarget {
  uint8_t *rgb = nullptr;      ///< 3 bytes per pixel, row-major, top row first; null: not kept
  float *opacity = nullptr;    ///< accumulated opacity per pixel; null: not kept
  uint32_t *samples = nullptr; ///< samples taken per pixel; null: not kept
  float *rgba = nullptr;       ///< premultiplied colour and opacity, before the background; null: not kept
  uint16_t *rgba16 = nullptr;  ///< the same, 65535 for 1; null: not kept
  int width = 0;
  Vec3f background;

  UVR_HOST_DEVICE static uint8_t toByte(float v) { return uint8_t(clampf(v, 0.f, 1.f) * 255.f + 0.5f); }
  UVR_HOST_DEVICE static uint16_t toChannel16(float v) {
    return uint16_t(clampf(v, 0.f, 1.f) * 65535.f + 0.5f);
  }

  /// Composites `result` over the background and stores it at (x, y).
  UVR_HOST_DEVICE void store(int x, int y, const RayResult &result) const {
    const uint64_t index = uint64_t(y) * uint64_t(width) + uint64_t(x);
    if (rgb) {
      const float transmittance = 1.f - result.color.w;
      rgb[3 * index + 0] = toByte(result.color.x + transmittance * background.x);
      rgb[3 * index + 1] = toByte(result.color.y + transmittance * background.y);
      rgb[3 * index + 2] = toByte(result.color.z + transmittance * background.z);
    }
    if (opacity)
      opacity[index] = result.color.w;
    if (samples)
      samples[index] = result.samples;
    if (rgba) {
      rgba[4 * index + 0] = result.color.x;
      rgba[4 * index + 1] = result.color.y;
      rgba[4 * index + 2] = result.color.z;
      rgba[4 * index + 3] = result.color.w;
    }
    if (rgba16) {
      rgba16[4 * index + 0] = toChannel16(result.color.x);
      rgba16[4 * index + 1] = toChannel16(result.color.y);
      rgba16[4 * index + 2] = toChannel16(result.color.z);
      rgba16[4 * index + 3] = toChannel16(result.color.w);
    }
  }
};

} // namespace uvr
