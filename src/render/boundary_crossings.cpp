#include "render/boundary_crossings.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

namespace uvr {

void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &start, std::vector<uint64_t> &keys) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  // The faces are tested once, each thread listing what it finds by band of image rows. Each band is then
  // sorted by pixel by counting, in a task of its own and so with plain increments on counts that stay in
  // cache: start[p + 1] counts pixel p's crossings, then holds where its run begins, and once they are
  // placed, where it ends (the next pixel's beginning); each pixel's run is then sorted by t.
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
  // Where each band's run of keys begins: after the crossings of all bands before it.
  std::vector<uint64_t> bandStart(bands + 1, 0);
  for (size_t band = 0; band < bands; ++band) {
    bandStart[band + 1] = bandStart[band];
    for (const std::vector<std::vector<Found>> &lists : found)
      bandStart[band + 1] += lists[band].size();
  }
  const uint64_t total = bandStart[bands];
  start.resize(pixels + 2);
  start[0] = 0;
  start[pixels + 1] = total;
  keys.resize(total);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, bands), [&](const tbb::blocked_range<size_t> &r) {
    for (size_t band = r.begin(); band < r.end(); ++band) {
      const size_t first = band * bandPixels, last = std::min(first + bandPixels, pixels);
      auto eachFound = [&](auto &&use) {
        for (const std::vector<std::vector<Found>> &lists : found)
          for (const Found &f : lists[band])
            use(f);
      };
      std::fill(start.begin() + first + 1, start.begin() + last + 1, uint64_t(0));
      eachFound([&](const Found &f) { ++start[f.pixel + 1]; });
      uint64_t begin = bandStart[band];
      for (size_t p = first; p < last; ++p)
        begin += std::exchange(start[p + 1], begin);
      eachFound([&](const Found &f) { keys[start[f.pixel + 1]++] = f.key; });
      // The band's first run begins where the band does: start[first] is the band before's to write.
      for (size_t p = first; p < last; ++p)
        std::sort(keys.begin() + (p == first ? bandStart[band] : start[p]), keys.begin() + start[p + 1]);
    }
  });
}

} // namespace uvr
