#include "render/pixel.h"
#include "render/renderer.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

namespace uvr {

void renderCpu(const SceneView &scene, const CameraView &camera, const RenderSettings &settings,
               const PixelTarget &target) {
  // Small tiles: rays through dense parts of the mesh cost far more than others, so balance finely.
  constexpr int kTile = 16;
  tbb::parallel_for(tbb::blocked_range2d<int>(0, settings.height, kTile, 0, settings.width, kTile),
                    [&](const tbb::blocked_range2d<int> &tile) {
                      uint32_t hint = kNoCell;
                      for (int y = tile.rows().begin(); y < tile.rows().end(); ++y)
                        for (int x = tile.cols().begin(); x < tile.cols().end(); ++x)
                          target.store(x, y,
                                       integrateRay(scene, settings.integrator, camera.ray(x, y), hint));
                    });
}

} // namespace uvr
