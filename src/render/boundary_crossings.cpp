#include "render/boundary_crossings.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <numeric>

namespace uvr {

void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &start, std::vector<uint64_t> &keys) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  auto eachCrossing = [&](auto &&visit) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size()), [&](const tbb::blocked_range<size_t> &r) {
      for (size_t i = r.begin(); i < r.end(); ++i)
        forEachPixelCrossing(mesh, faces[i], camera, visit);
    });
  };
  // start[p + 1] counts pixel p's crossings, then holds where its run begins, and once they are placed, where
  // it ends: the next pixel's beginning. The last entry ends up holding the total.
  start.assign(pixels + 2, 0);
  eachCrossing([&](uint64_t pixel, uint64_t) {
    std::atomic_ref<uint64_t>(start[pixel + 1]).fetch_add(1, std::memory_order_relaxed);
  });
  std::exclusive_scan(start.begin() + 1, start.end(), start.begin() + 1, uint64_t(0));
  keys.resize(start.back());
  eachCrossing([&](uint64_t pixel, uint64_t key) {
    keys[std::atomic_ref<uint64_t>(start[pixel + 1]).fetch_add(1, std::memory_order_relaxed)] = key;
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t p = r.begin(); p < r.end(); ++p)
      std::sort(keys.begin() + int64_t(start[p]), keys.begin() + int64_t(start[p + 1]));
  });
}

} // namespace uvr
