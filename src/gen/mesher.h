// Unstructured meshes made from structured volumes: what `uvr gen` builds (methods in tet_mesher.cpp and
// hex_mesher.cpp, and in docs/design.md).
#pragma once

#include "gen/volume.h"
#include "mesh/mesh.h"

#include <uvr/gen.h>

#include <cstdint>

namespace uvr {

/// splitmix64's finaliser: a well-mixed 64-bit hash, for jitter that depends on the inputs alone.
inline uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// Graded, conforming tetrahedral mesh of the part of `volume` that passes the threshold, with the volume
/// sampled trilinearly at the vertices as a point field named after the volume.
Mesh generateTetMesh(const Volume &volume, const GenOptions &options);

/// Graded, conforming hexahedral mesh (a tensor grid whose spacing follows the field's variation per axis).
Mesh generateHexMesh(const Volume &volume, const GenOptions &options);

/// The volume at each cell's centroid (the mean of its corners), as the cell field "<name>_cell".
ScalarField sampleCellCentroids(const Volume &volume, const Mesh &mesh);

/// The threshold a run uses: the option's, else Otsu's.
float effectiveThreshold(const Volume &volume, const GenOptions &options);

} // namespace uvr
