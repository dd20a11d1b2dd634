// Per tet, its barycentric weights and field as affine functions of position, in one cache line: a walk step
// on the host loads one record instead of four corner indices, four points and four values, and needs no
// division. 64 bytes per tet, so only the CPU keeps them; the GPU, held to 64 bytes per tet in all, computes
// the same from the corners.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

struct alignas(64) TetAffine {
  Vec3f corner;            ///< corner 0, where weights 1-3 are 0: weights taken from it keep their precision
  Vec3f weightGradient[3]; ///< of weights 1, 2, 3 (weight 0 is 1 minus their sum); NaN for a flat tet
  Vec3f valueGradient;     ///< zero for cell data
  float valueAtCorner;

  /// Weights of `p` and their change per unit step along `direction`, as tetBarycentricsAlong gives them;
  /// false for a flat tet.
  UVR_HOST_DEVICE bool weightsAlong(Vec3f p, Vec3f direction, float w[4], float dw[4]) const {
    const Vec3f q = p - corner;
    for (int i = 0; i < 3; ++i) {
      w[i + 1] = dot(weightGradient[i], q);
      dw[i + 1] = dot(weightGradient[i], direction);
    }
    w[0] = 1.f - w[1] - w[2] - w[3];
    dw[0] = -dw[1] - dw[2] - dw[3];
    return w[0] == w[0];
  }
  /// The field at `p` and its change per unit step along `direction`.
  UVR_HOST_DEVICE void valueAlong(Vec3f p, Vec3f direction, float &value, float &slope) const {
    value = valueAtCorner + dot(valueGradient, p - corner);
    slope = dot(valueGradient, direction);
  }
};
static_assert(sizeof(TetAffine) == 64);

/// The records of `mesh`'s tets, for its field (as makeMeshView chose it), on all cores.
std::vector<TetAffine> buildTetAffine(const MeshView &mesh);

} // namespace uvr
