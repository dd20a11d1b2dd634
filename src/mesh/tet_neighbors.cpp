#include "mesh/tet_neighbors.h"

#include "core/progress.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <atomic>

namespace uvr {

std::vector<uint32_t> buildTetNeighbors(const Mesh &mesh) {
  const uint64_t tetCount = mesh.tetCount();
  const uint64_t entryCount = 4 * tetCount;
  const size_t pointCount = mesh.points.size();
  const uint32_t *tets = mesh.tets.data();

  // Point -> incident tets, as compressed rows: counted, offset, then filled, each in parallel. The order
  // within a row depends on the threads' timing; the search below does not.
  std::vector<uint64_t> first(pointCount + 1, 0);
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, entryCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      for (uint64_t i = range.begin(); i < range.end(); ++i)
                        std::atomic_ref<uint64_t>(first[tets[i] + 1]).fetch_add(1, std::memory_order_relaxed);
                    });
  tbb::parallel_scan(
      tbb::blocked_range<size_t>(1, pointCount + 1), uint64_t(0),
      [&](const tbb::blocked_range<size_t> &range, uint64_t sum, bool final) {
        for (size_t p = range.begin(); p < range.end(); ++p) {
          sum += first[p];
          if (final)
            first[p] = sum;
        }
        return sum;
      },
      std::plus<uint64_t>());
  std::vector<uint32_t> incident(entryCount);
  {
    std::vector<uint64_t> next(first.begin(), first.end() - 1);
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, entryCount),
                      [&](const tbb::blocked_range<uint64_t> &range) {
                        for (uint64_t i = range.begin(); i < range.end(); ++i) {
                          std::atomic_ref<uint64_t> slot(next[tets[i]]);
                          incident[slot.fetch_add(1, std::memory_order_relaxed)] = uint32_t(i / 4);
                        }
                      });
  }

  std::vector<uint32_t> neighbors(entryCount);
  Progress progress("building tet adjacency", tetCount);
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, tetCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      for (uint64_t t = range.begin(); t < range.end(); ++t) {
                        uint32_t across[4];
                        findTetNeighbors(tets, t, first.data(), incident.data(), across);
                        std::copy_n(across, 4, neighbors.begin() + 4 * t);
                      }
                      progress.advance(range.size());
                    });
  progress.finish();
  return neighbors;
}

std::vector<uint32_t> listBoundaryFaces(const std::vector<uint32_t> &tetNeighbors) {
  std::vector<uint32_t> faces;
  for (size_t entry = 0; entry < tetNeighbors.size(); ++entry)
    if (tetNeighbors[entry] == 0xffffffffu)
      faces.push_back(uint32_t(entry));
  return faces;
}

} // namespace uvr
