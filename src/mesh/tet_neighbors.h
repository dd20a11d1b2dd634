// Face adjacency of the tetrahedra, for walking from one sample's cell to the next.
#pragma once

#include "core/host_device.h"
#include "mesh/mesh.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// For each tet and each of its vertices i, the tet across the face opposite vertex i, or 0xffffffff on the
/// boundary: 4 entries per tet, indexed as the cells are.
std::vector<uint32_t> buildTetNeighbors(const Mesh &mesh);

/// The tet faces with no neighbour (the boundary faces), numbered 4 * tet + i for the face opposite corner
/// i, in increasing order; `tetNeighbors` as buildTetNeighbors gives them, for fewer than 2^30 tets.
std::vector<uint32_t> listBoundaryFaces(const std::vector<uint32_t> &tetNeighbors);

UVR_HOST_DEVICE inline bool tetHolds(const uint32_t *tet, uint32_t point) {
  return (tet[0] == point) | (tet[1] == point) | (tet[2] == point) | (tet[3] == point);
}

/// The neighbours of tet `t` into `across`, given each point's incident tets as compressed rows
/// (incident[first[p], first[p + 1])). The tet across a face is the smallest other tet holding its three
/// points. Face 0 (opposite corner 0) holds corner 1 and the others hold corner 0, so the rows of these two
/// corners list every candidate; each is tested against all the faces it may share at once, without
/// branches. Shared by the host's build and the GPU's.
UVR_HOST_DEVICE inline void findTetNeighbors(const uint32_t *tets, uint64_t t, const uint64_t *first,
                                             const uint32_t *incident, uint32_t across[4]) {
  auto smaller = [](uint32_t a, uint32_t b) { return a < b ? a : b; };
  const uint32_t *v = tets + 4 * t;
  for (int i = 0; i < 4; ++i)
    across[i] = 0xffffffffu;
  for (uint64_t k = first[v[1]]; k < first[v[1] + 1]; ++k) {
    const uint32_t other = incident[k];
    const uint32_t *w = tets + 4 * uint64_t(other);
    const bool self = other == t, has2 = tetHolds(w, v[2]), has3 = tetHolds(w, v[3]);
    across[0] = (!self & has2 & has3) ? smaller(across[0], other) : across[0];
  }
  for (uint64_t k = first[v[0]]; k < first[v[0] + 1]; ++k) {
    const uint32_t other = incident[k];
    const uint32_t *w = tets + 4 * uint64_t(other);
    const bool self = other == t, has1 = tetHolds(w, v[1]), has2 = tetHolds(w, v[2]),
               has3 = tetHolds(w, v[3]);
    across[1] = (!self & has2 & has3) ? smaller(across[1], other) : across[1];
    across[2] = (!self & has3 & has1) ? smaller(across[2], other) : across[2];
    across[3] = (!self & has1 & has2) ? smaller(across[3], other) : across[3];
  }
}

} // namespace uvr
