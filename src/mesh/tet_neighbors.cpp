#include "mesh/tet_neighbors.h"

#include "core/progress.h"

#include <tbb/parallel_for.h>

namespace uvr {

std::vector<uint32_t> buildTetNeighbors(const Mesh &mesh) {
  const uint64_t tetCount = mesh.tetCount();
  const uint32_t *tets = mesh.tets.data();

  // Point -> incident tets, as compressed rows.
  std::vector<uint64_t> first(mesh.points.size() + 1, 0);
  for (uint64_t i = 0; i < 4 * tetCount; ++i)
    ++first[tets[i] + 1];
  for (size_t p = 0; p < mesh.points.size(); ++p)
    first[p + 1] += first[p];
  std::vector<uint32_t> incident(4 * tetCount);
  {
    std::vector<uint64_t> next(first.begin(), first.end() - 1);
    for (uint64_t i = 0; i < 4 * tetCount; ++i)
      incident[next[tets[i]]++] = uint32_t(i / 4);
  }

  // Incidence rows come out sorted (tets are visited in order), so the tets sharing a face are found by
  // merging two rows and checking the third point.
  std::vector<uint32_t> neighbors(4 * tetCount, 0xffffffffu);
  Progress progress("building tet adjacency", tetCount);
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, tetCount),
                    [&](const tbb::blocked_range<uint64_t> &range) {
                      for (uint64_t t = range.begin(); t < range.end(); ++t) {
                        const uint32_t *v = tets + 4 * t;
                        for (int face = 0; face < 4; ++face) {
                          const uint32_t a = v[(face + 1) % 4], b = v[(face + 2) % 4], c = v[(face + 3) % 4];
                          uint64_t i = first[b], j = first[c];
                          const uint64_t iEnd = first[b + 1], jEnd = first[c + 1];
                          while (i < iEnd && j < jEnd) {
                            if (incident[i] < incident[j]) {
                              ++i;
                            } else if (incident[j] < incident[i]) {
                              ++j;
                            } else {
                              const uint32_t other = incident[i];
                              const uint32_t *w = tets + 4 * uint64_t(other);
                              if (other != t && (w[0] == a || w[1] == a || w[2] == a || w[3] == a)) {
                                neighbors[4 * t + uint64_t(face)] = other;
                                break;
                              }
                              ++i, ++j;
                            }
                          }
                        }
                      }
                      progress.advance(range.size());
                    });
  progress.finish();
  return neighbors;
}

} // namespace uvr
