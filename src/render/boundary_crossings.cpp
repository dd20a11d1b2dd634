#include "render/boundary_crossings.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

namespace uvr {

void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &start, std::vector<uint64_t> &keys) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  // The faces are tested once, each thread listing what it finds by band of image rows; the lists are then
  // sorted by pixel by counting, a band per task, so with plain increments (start[p + 1] counts pixel p's
  // crossings, then holds where its run begins, and once they are placed, where it ends: the next pixel's
  // beginning; the last entry ends up holding the total), and each pixel's run by t.
  struct Found {
    uint64_t pixel, key;
  };
  constexpr size_t kBandRows = 16;
  const size_t bandPixels = kBandRows * size_t(camera.width);
  const size_t bands = (pixels + bandPixels - 1) / bandPixels;
  tbb::enumerable_thread_specific<std::vector<std::vector<Found>>> found(
      [&] { return std::vector<std::vector<Found>>(bands); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, faces.size()), [&](const tbb::blocked_range<size_t> &r) {
    std::vector<std::vector<Found>> &mine = found.local();
    for (size_t i = r.begin(); i < r.end(); ++i)
      forEachPixelCrossing(mesh, faces[i], camera, [&](uint64_t pixel, uint64_t key) {
        mine[pixel / bandPixels].push_back({pixel, key});
      });
  });
  auto eachBand = [&](auto &&use) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, bands), [&](const tbb::blocked_range<size_t> &r) {
      for (size_t band = r.begin(); band < r.end(); ++band)
        for (const std::vector<std::vector<Found>> &lists : found)
          for (const Found &f : lists[band])
            use(f);
    });
  };
  start.assign(pixels + 2, 0);
  eachBand([&](const Found &f) { ++start[f.pixel + 1]; });
  std::exclusive_scan(start.begin() + 1, start.end(), start.begin() + 1, uint64_t(0));
  keys.resize(start.back());
  eachBand([&](const Found &f) { keys[start[f.pixel + 1]++] = f.key; });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t p = r.begin(); p < r.end(); ++p)
      std::sort(keys.begin() + int64_t(start[p]), keys.begin() + int64_t(start[p + 1]));
  });
}

} // namespace uvr
