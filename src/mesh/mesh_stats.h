// Measures of a mesh that defaults and `uvr info` rest on.
#pragma once

#include "mesh/mesh.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace uvr {

/// Volume of one cell (absolute; hexahedra, wedges and pyramids through a split into tetrahedra).
double cellVolume(const MeshView &mesh, uint64_t cell);

VolumeStats volumeStats(const Mesh &mesh);

/// The value of rank `rank` (< count) among value(0 .. count - 1), as std::nth_element finds it, without
/// keeping the values: a radix select over their bits, each pass computing them again, until at most
/// `gatherAtMost` are left to gather and select among.
double selectRank(uint64_t count, uint64_t rank, const std::function<double(uint64_t)> &value,
                  uint64_t gatherAtMost = uint64_t(1) << 22);

/// selectRank for each of `ranks` at once: the searches that stand at the same digits share each pass.
std::vector<double> selectRanks(uint64_t count, const std::vector<uint64_t> &ranks,
                                const std::function<double(uint64_t)> &value,
                                uint64_t gatherAtMost = uint64_t(1) << 22);

/// Range of a field's finite values; {0, 0} when it has none.
ValueRange valueRange(const ScalarField &field);

/// The default step s1: the edge of a cube of the median volume per tetrahedron (VolumeStats::medianPerTet),
/// about half a typical tet's edge, so that a ray takes about two samples per cell it crosses; but at least
/// 1/10^4 of the bounds' diagonal, so that no ray of a mesh with tiny or degenerate cells takes more samples,
/// and at most a quarter of the bounds' thinnest side, so that a mesh of a few cells is sampled through.
/// 0 where the bounds are empty or a point.
float defaultStepSize(const VolumeStats &volumes, const Box3f &bounds);

} // namespace uvr
