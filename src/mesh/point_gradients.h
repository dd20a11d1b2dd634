// The field's gradient per point, for gradient shading (render/shading.h).
#pragma once

#include "core/vec.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// The gradient of `view`'s field at each of its `pointCount` points: the mean of the gradients of the cells
/// around the point, each weighted by its volume. A tet's gradient is exact (the field is linear in it);
/// another cell's is taken at its parametric centre. Cell data is first averaged to the points (each cell
/// weighted by its volume) and the gradient is that of the averaged field. A point no cell uses, or only
/// flat ones, gets 0.
std::vector<Vec3f> computePointGradients(const MeshView &view, uint64_t pointCount);

} // namespace uvr
