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

  /// Weights of `p` (NaN for a flat tet) and the field there. Host only: the GPU keeps no records.
  void at(Vec3f p, float w[4], float &value) const {
    const Lanes a = gradientsDot(p - corner);
    w[0] = 1.f - a[0] - a[1] - a[2];
    for (int i = 1; i < 4; ++i)
      w[i] = a[i - 1];
    value = valueAtCorner + a[3];
  }
  /// Weights of `p` and their change per unit step along `direction`, as tetBarycentricsAlong gives them,
  /// and the field there and its change; false for a flat tet. Host only, as at().
  bool along(Vec3f p, Vec3f direction, float w[4], float dw[4], float &value, float &slope) const {
    at(p, w, value);
    const Lanes change = gradientsDot(direction);
    dw[0] = -change[0] - change[1] - change[2];
    for (int i = 1; i < 4; ++i)
      dw[i] = change[i - 1];
    slope = change[3];
    return w[0] == w[0];
  }

private:
  using Lanes = float __attribute__((vector_size(16)));
  /// The four functions' gradients dotted with `v`: weights 1-3 in lanes 0-2, the field in lane 3.
  Lanes gradientsDot(Vec3f v) const {
    Lanes x, y, z;
    memcpy(&x, gradientX, sizeof x);
    memcpy(&y, gradientY, sizeof y);
    memcpy(&z, gradientZ, sizeof z);
    return x * v.x + y * v.y + z * v.z;
  }
};
static_assert(sizeof(TetAffine) == 64);

/// The records of `mesh`'s tets, for its field (as makeMeshView chose it), on all cores.
std::vector<TetAffine> buildTetAffine(const MeshView &mesh);

} // namespace uvr
