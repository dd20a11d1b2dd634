#include "render/renderer.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace uvr {

namespace {
uint8_t toByte(float v) { return uint8_t(std::lround(std::clamp(v, 0.f, 1.f) * 255.f)); }
} // namespace

void renderCpu(const SceneView &scene, const CameraView &camera, const RenderSettings &settings,
               Frame &frame) {
  // Small tiles: rays through dense parts of the mesh cost far more than others, so balance finely.
  constexpr int kTile = 16;
  tbb::parallel_for(tbb::blocked_range2d<int>(0, settings.height, kTile, 0, settings.width, kTile),
                    [&](const tbb::blocked_range2d<int> &tile) {
                      uint32_t hint = kNoCell;
                      for (int y = tile.rows().begin(); y < tile.rows().end(); ++y)
                        for (int x = tile.cols().begin(); x < tile.cols().end(); ++x) {
                          const RayResult r =
                              integrateRay(scene, settings.integrator, camera.ray(x, y), hint);
                          const float transmittance = 1.f - r.color.w;
                          uint8_t *pixel = frame.image.pixel(x, y);
                          pixel[0] = toByte(r.color.x + transmittance * settings.background.x);
                          pixel[1] = toByte(r.color.y + transmittance * settings.background.y);
                          pixel[2] = toByte(r.color.z + transmittance * settings.background.z);
                          const size_t index = size_t(y) * size_t(settings.width) + size_t(x);
                          frame.opacity[index] = r.color.w;
                          frame.samplesPerPixel[index] = r.samples;
                        }
                    });
}

} // namespace uvr
