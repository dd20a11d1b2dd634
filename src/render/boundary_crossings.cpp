#include "render/boundary_crossings.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <numeric>

namespace uvr {

void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &start, std::vector<uint64_t> &keys) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  // The faces are tested once, each thread listing what it finds; the lists are then sorted by pixel by
  // counting (start[p + 1] counts pixel p's crossings, then holds where its run begins, and once they are
  // placed, where it ends: the next pixel's beginning; the last entry ends up holding the total), and each
  // pixel's run by t.
  struct Found {
    uint64_t pixel, key;
  };
  tbb::enumerable_thread_specific<std::vector<Found>> found;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size()), [&](const tbb::blocked_range<size_t> &r) {
    std::vector<Found> &mine = found.local();
    for (size_t i = r.begin(); i < r.end(); ++i)
      forEachPixelCrossing(mesh, faces[i], camera, [&](uint64_t pixel, uint64_t key) {
        mine.push_back({pixel, key});
      });
  });
  auto eachFound = [&](auto &&use) {
    for (const std::vector<Found> &list : found)
      tbb::parallel_for(tbb::blocked_range<size_t>(0, list.size()), [&](const tbb::blocked_range<size_t> &r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
          use(list[i]);
      });
  };
  start.assign(pixels + 2, 0);
  eachFound([&](const Found &f) {
    std::atomic_ref<uint64_t>(start[f.pixel + 1]).fetch_add(1, std::memory_order_relaxed);
  });
  std::exclusive_scan(start.begin() + 1, start.end(), start.begin() + 1, uint64_t(0));
  keys.resize(start.back());
  eachFound([&](const Found &f) {
    keys[std::atomic_ref<uint64_t>(start[f.pixel + 1]).fetch_add(1, std::memory_order_relaxed)] = f.key;
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t p = r.begin(); p < r.end(); ++p)
      std::sort(keys.begin() + int64_t(start[p]), keys.begin() + int64_t(start[p + 1]));
  });
}

} // namespace uvr
