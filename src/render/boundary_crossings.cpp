#include "render/boundary_crossings.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>

namespace uvr {

void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &first, std::vector<uint32_t> &last) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  first.assign(pixels, kNoCrossing);
  last.assign(pixels, kNoLastCrossing);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, faces.size()), [&](const tbb::blocked_range<size_t> &range) {
        for (size_t i = range.begin(); i < range.end(); ++i)
          forEachPixelCrossing(mesh, faces[i], camera, [&](int x, int y, float t) {
            const size_t pixel = size_t(y) * size_t(camera.width) + size_t(x);
            const uint64_t key = crossingKey(t, faces[i]);
            std::atomic_ref<uint64_t> least(first[pixel]);
            for (uint64_t seen = least.load(std::memory_order_relaxed);
                 key < seen && !least.compare_exchange_weak(seen, key, std::memory_order_relaxed);)
              ;
            const uint32_t bits = floatBits(t);
            std::atomic_ref<uint32_t> largest(last[pixel]);
            for (uint32_t seen = largest.load(std::memory_order_relaxed);
                 bits > seen && !largest.compare_exchange_weak(seen, bits, std::memory_order_relaxed);)
              ;
          });
      });
}

} // namespace uvr
