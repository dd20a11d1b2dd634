// Per tet, its barycentric weights and field as affine functions of position, in one cache line: a walk step
// on the host loads one record instead of four corner indices, four points and four values, and needs no
// division. 64 bytes per tet, so only the CPU keeps them; the GPU, held to 64 bytes per tet in all, computes
// the same from the corners.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <cstring>
#include <vector>

namespace uvr {

struct alignas(64) TetAffine {
  Vec3f corner;        ///< corner 0, where weights 1-3 are 0: weights taken from it keep their precision
  float valueAtCorner; ///< the field there
  /// The gradients of weights 1, 2, 3 (weight 0 is 1 minus their sum; NaN for a flat tet) and of the field
  /// (zero for cell data), by axis: lane i of each axis belongs to one function, so that all four come
  /// out of three 4-wide multiply-adds.
  float gradientX[4], gradientY[4], gradientZ[4];

  /// Weights of `p` and their change per unit step along `direction`, as tetBarycentricsAlong gives them,
  /// and the field there and its change; false for a flat tet. Host only: the GPU keeps no records.
  bool along(Vec3f p, Vec3f direction, float w[4], float dw[4], float &value, float &slope) const {
    using Lanes = float __attribute__((vector_size(16)));
    Lanes x, y, z;
    memcpy(&x, gradientX, sizeof x);
    memcpy(&y, gradientY, sizeof y);
    memcpy(&z, gradientZ, sizeof z);
    const Vec3f q = p - corner;
    const Lanes at = x * q.x + y * q.y + z * q.z;
    const Lanes change = x * direction.x + y * direction.y + z * direction.z;
    w[0] = 1.f - at[0] - at[1] - at[2];
    dw[0] = -change[0] - change[1] - change[2];
    for (int i = 1; i < 4; ++i) {
      w[i] = at[i - 1];
      dw[i] = change[i - 1];
    }
    value = valueAtCorner + at[3];
    slope = change[3];
    return w[0] == w[0];
  }
};
static_assert(sizeof(TetAffine) == 64);

/// The records of `mesh`'s tets, for its field (as makeMeshView chose it), on all cores.
std::vector<TetAffine> buildTetAffine(const MeshView &mesh);

} // namespace uvr
