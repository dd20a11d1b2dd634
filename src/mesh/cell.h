// Point location inside one cell and interpolation of the field there, for the four VTK volume cell types.
// Tetrahedra are linear (barycentric); hexahedra, wedges and pyramids use VTK's isoparametric shape
// functions, inverted by Newton iteration.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"

namespace uvr {

/// How far outside [0, 1] a parametric coordinate may lie and still count as inside: points on a face shared
/// by two cells must be found in one of them despite rounding.
constexpr float kInsideTolerance = 1e-5f;

/// No cell: a cell index that lies past every mesh's last.
constexpr uint32_t kNoCell = 0xffffffffu;

UVR_HOST_DEVICE inline float det3(Vec3f a, Vec3f b, Vec3f c) { return dot(a, cross(b, c)); }

/// Barycentric weights `w` of `p` in tetrahedron (a, b, c, d), inside or not, and their change `dw` per unit
/// step along `direction`: the weights of p + s * direction are w + s * dw. False when the cell is flat.
UVR_HOST_DEVICE inline bool tetBarycentricsAlong(Vec3f a, Vec3f b, Vec3f c, Vec3f d, Vec3f p, Vec3f direction,
                                                 float w[4], float dw[4]) {
  const Vec3f e1 = b - a, e2 = c - a, e3 = d - a;
  // The weights' gradients times the volume: the rows of the inverse of [e1 e2 e3], times its determinant.
  const Vec3f g1 = cross(e2, e3), g2 = cross(e3, e1), g3 = cross(e1, e2);
  const float volume = dot(e1, g1);
  if (!(volume != 0.f))
    return false;
  const float inv = 1.f / volume;
  const Vec3f q = p - a;
  w[1] = dot(g1, q) * inv;
  w[2] = dot(g2, q) * inv;
  w[3] = dot(g3, q) * inv;
  w[0] = 1.f - w[1] - w[2] - w[3];
  dw[1] = dot(g1, direction) * inv;
  dw[2] = dot(g2, direction) * inv;
  dw[3] = dot(g3, direction) * inv;
  dw[0] = -dw[1] - dw[2] - dw[3];
  return true;
}

/// Barycentric weights of `p` in tetrahedron (a, b, c, d), inside or not; false when the cell is flat.
UVR_HOST_DEVICE inline bool tetBarycentrics(Vec3f a, Vec3f b, Vec3f c, Vec3f d, Vec3f p, float w[4]) {
  float unused[4]; // computed, then dropped by the compiler
  return tetBarycentricsAlong(a, b, c, d, p, Vec3f{}, w, unused);
}

/// Index of the smallest weight: the face (opposite that vertex) the point lies furthest beyond; and the
/// weight itself in `lowest`. Ties go to the lower index. Selects, not branches: which face a walk leaves by
/// is unpredictable; and no array indexed at run time, which a GPU would keep in local memory.
UVR_HOST_DEVICE inline int smallestWeight(const float w[4], float &lowest) {
  const bool low1 = w[1] < w[0], low3 = w[3] < w[2];
  const float lowest01 = low1 ? w[1] : w[0], lowest23 = low3 ? w[3] : w[2];
  const bool low23 = lowest23 < lowest01;
  lowest = low23 ? lowest23 : lowest01;
  return low23 ? 2 + int(low3) : int(low1);
}

/// The face by which a ray leaves a tet on its way to a point beyond it, given the point's weights `w` and
/// their change `dw` per unit step along the ray: of the faces the point lies beyond (w < 0) and the ray
/// runs out through (dw < 0), the one crossed first, farthest back from the point (largest w / dw). Where
/// none is (rounding, or a tet the ray misses), `otherwise`.
UVR_HOST_DEVICE inline int rayExitFace(const float w[4], const float dw[4], int otherwise) {
  float ahead[4]; // where the ray crosses each face, from the point on: negative behind it
  for (int i = 0; i < 4; ++i)
    ahead[i] = w[i] < 0.f && dw[i] < 0.f ? -w[i] / dw[i] : 1.f;
  float nearest;
  const int face = smallestWeight(ahead, nearest);
  return nearest <= 0.f ? face : otherwise;
}

/// Barycentric weights of `p` in tetrahedron (a, b, c, d); false when `p` is outside or the cell is flat.
UVR_HOST_DEVICE inline bool tetWeights(Vec3f a, Vec3f b, Vec3f c, Vec3f d, Vec3f p, float w[4]) {
  if (!tetBarycentrics(a, b, c, d, p, w))
    return false;
  float lowest;
  smallestWeight(w, lowest);
  return lowest >= -kInsideTolerance;
}

/// VTK's shape functions and their parametric derivatives for the non-simplex cells.
template <int N> struct ShapeFunctions {
  float value[N];
  Vec3f derivative[N];
};

UVR_HOST_DEVICE inline void hexShape(Vec3f r, ShapeFunctions<8> &s) {
  const float u = r.x, v = r.y, w = r.z, iu = 1.f - u, iv = 1.f - v, iw = 1.f - w;
  s.value[0] = iu * iv * iw;
  s.value[1] = u * iv * iw;
  s.value[2] = u * v * iw;
  s.value[3] = iu * v * iw;
  s.value[4] = iu * iv * w;
  s.value[5] = u * iv * w;
  s.value[6] = u * v * w;
  s.value[7] = iu * v * w;
  s.derivative[0] = {-iv * iw, -iu * iw, -iu * iv};
  s.derivative[1] = {iv * iw, -u * iw, -u * iv};
  s.derivative[2] = {v * iw, u * iw, -u * v};
  s.derivative[3] = {-v * iw, iu * iw, -iu * v};
  s.derivative[4] = {-iv * w, -iu * w, iu * iv};
  s.derivative[5] = {iv * w, -u * w, u * iv};
  s.derivative[6] = {v * w, u * w, u * v};
  s.derivative[7] = {-v * w, iu * w, iu * v};
}

UVR_HOST_DEVICE inline void wedgeShape(Vec3f r, ShapeFunctions<6> &s) {
  const float u = r.x, v = r.y, w = r.z, b = 1.f - u - v, iw = 1.f - w;
  s.value[0] = b * iw;
  s.value[1] = u * iw;
  s.value[2] = v * iw;
  s.value[3] = b * w;
  s.value[4] = u * w;
  s.value[5] = v * w;
  s.derivative[0] = {-iw, -iw, -b};
  s.derivative[1] = {iw, 0.f, -u};
  s.derivative[2] = {0.f, iw, -v};
  s.derivative[3] = {-w, -w, b};
  s.derivative[4] = {w, 0.f, u};
  s.derivative[5] = {0.f, w, v};
}

UVR_HOST_DEVICE inline void pyramidShape(Vec3f r, ShapeFunctions<5> &s) {
  const float u = r.x, v = r.y, w = r.z, iu = 1.f - u, iv = 1.f - v, iw = 1.f - w;
  s.value[0] = iu * iv * iw;
  s.value[1] = u * iv * iw;
  s.value[2] = u * v * iw;
  s.value[3] = iu * v * iw;
  s.value[4] = w;
  s.derivative[0] = {-iv * iw, -iu * iw, -iu * iv};
  s.derivative[1] = {iv * iw, -u * iw, -u * iv};
  s.derivative[2] = {v * iw, u * iw, -u * v};
  s.derivative[3] = {-v * iw, iu * iw, -iu * v};
  s.derivative[4] = {0.f, 0.f, 1.f};
}

UVR_HOST_DEVICE inline void evaluateShape(Vec3f r, ShapeFunctions<8> &s) { hexShape(r, s); }
UVR_HOST_DEVICE inline void evaluateShape(Vec3f r, ShapeFunctions<6> &s) { wedgeShape(r, s); }
UVR_HOST_DEVICE inline void evaluateShape(Vec3f r, ShapeFunctions<5> &s) { pyramidShape(r, s); }

/// Whether parametric coordinates lie in the reference cell (unit cube, unit prism, or unit pyramid).
UVR_HOST_DEVICE inline bool insideReference(Vec3f r, int n) {
  const float lo = -kInsideTolerance, hi = 1.f + kInsideTolerance;
  const bool inCube = r.x >= lo && r.y >= lo && r.z >= lo && r.x <= hi && r.y <= hi && r.z <= hi;
  return n == 6 ? inCube && r.x + r.y <= hi : inCube;
}

/// What a walk along a ray adds to a solve (parametricCoordinates). Samples lie about half a cell apart, so
/// a cell mostly holds the next sample too, whose solve then starts from this one's coordinates carried
/// along the ray by their rate, a fraction of a Newton step from its root. And a point outside the cell
/// still gets coordinates where the walk asks: they say which face it lies beyond.
struct RaySolve {
  Vec3f direction;       ///< the ray's
  Vec3f start;           ///< where `warm`, the iteration's start
  Vec3f rate;            ///< out: the root's change per unit step along `direction`
  bool warm = false;     ///< else the iteration starts at the reference cell's centre
  bool anywhere = false; ///< coordinates wanted for a point outside the cell's box too
};

/// Inverts x(r) = sum_i N_i(r) p_i by Newton's method: the parametric coordinates `r` of `p`; false where `p`
/// lies outside the cell's box, the iteration runs far outside the reference cell or does not converge, or
/// the cell is degenerate. The caller tells inside from outside (insideReference). `along`, where given,
/// gives the start and takes the rate (RaySolve); where it asks for coordinates `anywhere`, the box is not a
/// reason to stop, and where `p` lies outside it or the iteration fails, `r` is the last iterate (one step,
/// outside the box), which says which way `p` lies.
template <int N>
UVR_HOST_DEVICE inline bool parametricCoordinates(const Vec3f *points, const uint32_t *v, Vec3f p, Vec3f &r,
                                                  RaySolve *along = nullptr) {
  Vec3f corner[N];
  Vec3f lower = points[v[0]], upper = points[v[0]];
  for (int i = 0; i < N; ++i) {
    corner[i] = points[v[i]];
    lower = vmin(lower, corner[i]);
    upper = vmax(upper, corner[i]);
  }
  const Vec3f extent = upper - lower;
  const float scale = maxf(extent.x, maxf(extent.y, extent.z));
  if (!(scale > 0.f))
    return false;
  const float slack = scale * kInsideTolerance;
  const bool outsideBox = p.x < lower.x - slack || p.y < lower.y - slack || p.z < lower.z - slack ||
                          p.x > upper.x + slack || p.y > upper.y + slack || p.z > upper.z + slack;
  if (outsideBox && !(along && along->anywhere))
    return false;
  // About the first corner: far from the origin, absolute coordinates would leave the residual's rounding
  // above the tolerance below, and the iteration would never see it converge.
  const Vec3f origin = corner[0];
  for (int i = 0; i < N; ++i)
    corner[i] = corner[i] - origin;
  p = p - origin;

  // A hexahedron's map as a polynomial, x = b u + c v + d w + e uv + f vw + g uw + h uvw about corner 0: an
  // iteration then costs half of what its shape functions' sums do.
  Vec3f b, c, d, e, f, g, h;
  if constexpr (N == 8) {
    b = corner[1], c = corner[3], d = corner[4];
    e = corner[2] - corner[1] - corner[3];
    f = corner[7] - corner[3] - corner[4];
    g = corner[5] - corner[1] - corner[4];
    h = corner[6] - corner[2] - corner[5] - corner[7] + corner[1] + corner[3] + corner[4];
  }
  // Inside all three reference cells, away from the pyramid's apex; a hexahedron's centre, from which a
  // damped step reaches any point of the cube.
  r = along && along->warm ? along->start
      : N == 8             ? Vec3f{0.5f, 0.5f, 0.5f}
                           : Vec3f{1.f / 3.f, 1.f / 3.f, 0.5f};
  bool converged = false;
  Vec3f dr, ds, dt; // the Jacobian's columns, at the last iterate
  // Outside the box, one step tells a walk which way the point lies.
  const int iterations = outsideBox ? 1 : 16;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    Vec3f residual;
    dr = ds = dt = Vec3f{};
    if constexpr (N == 8) {
      const float u = r.x, v = r.y, w = r.z;
      residual = b * u + c * v + d * w + e * (u * v) + f * (v * w) + g * (u * w) + h * (u * v * w) - p;
      dr = b + e * v + g * w + h * (v * w);
      ds = c + e * u + f * w + h * (u * w);
      dt = d + f * v + g * u + h * (u * v);
    } else {
      ShapeFunctions<N> s; // the iteration's own: the caller evaluates the weights once, where it needs them
      evaluateShape(r, s);
      residual = Vec3f{} - p;
      for (int i = 0; i < N; ++i) {
        residual = residual + corner[i] * s.value[i];
        dr = dr + corner[i] * s.derivative[i].x;
        ds = ds + corner[i] * s.derivative[i].y;
        dt = dt + corner[i] * s.derivative[i].z;
      }
    }
    // Converged; also the way out at a pyramid's apex, where the Jacobian is singular.
    if (fabsf(residual.x) + fabsf(residual.y) + fabsf(residual.z) <= 1e-6f * scale) {
      converged = true;
      break;
    }
    // Solve J * delta = residual by Cramer's rule; J's columns are dx/dr, dx/ds, dx/dt.
    const float det = det3(dr, ds, dt);
    if (!(det != 0.f))
      return false;
    const float inv = 1.f / det;
    Vec3f delta{det3(residual, ds, dt) * inv, det3(dr, residual, dt) * inv, det3(dr, ds, residual) * inv};
    // Damped: on strongly distorted cells a full step from the centre can overshoot into another root. Not
    // the step that says which way a point outside the box lies.
    const float largest = maxf(fabsf(delta.x), maxf(fabsf(delta.y), fabsf(delta.z)));
    if (largest > 0.5f && !outsideBox)
      delta = delta * (0.5f / largest);
    r = r - delta;
    // Converging quadratically, a step this short leaves an error of about its square: a further residual
    // would only confirm it.
    if (largest <= 1e-4f) {
      converged = true;
      break;
    }
    // Far outside after a few steps: no need to converge to say no.
    if (iteration >= 3 && (fabsf(r.x - 0.5f) > 2.f || fabsf(r.y - 0.5f) > 2.f || fabsf(r.z - 0.5f) > 2.f))
      return false;
  }
  // At a pyramid's apex every (r, s) maps to the same point, and Newton's r and s wander off.
  if (N == 5 && r.z >= 1.f - 1e-4f && r.z <= 1.f + kInsideTolerance) {
    r.x = clampf(r.x, 0.f, 1.f);
    r.y = clampf(r.y, 0.f, 1.f);
  }
  if (along && converged) {
    const float det = det3(dr, ds, dt);
    const Vec3f d = along->direction;
    along->rate =
        det != 0.f ? Vec3f{det3(d, ds, dt), det3(dr, d, dt), det3(dr, ds, d)} * (1.f / det) : Vec3f{};
  }
  // Unconverged, r says nothing of where `p` lies: near a distorted cell the damped steps can stall inside
  // the reference cell with `p` outside.
  return converged;
}

/// The shape functions' weights at `p` into `s`; false where `p` lies outside the cell.
template <int N>
UVR_HOST_DEVICE inline bool isoparametricWeights(const Vec3f *points, const uint32_t *v, Vec3f p,
                                                 ShapeFunctions<N> &s) {
  Vec3f r;
  if (!parametricCoordinates<N>(points, v, p, r) || !insideReference(r, N))
    return false;
  evaluateShape(r, s);
  return true;
}

/// Which type a cell index falls on: cells are numbered tets, pyramids, wedges, hexahedra.
UVR_HOST_DEVICE inline CellType cellType(const MeshView &mesh, uint64_t cell) {
  if (cell < mesh.tetCount)
    return CellType::Tetra;
  cell -= mesh.tetCount;
  if (cell < mesh.pyramidCount)
    return CellType::Pyramid;
  cell -= mesh.pyramidCount;
  return cell < mesh.wedgeCount ? CellType::Wedge : CellType::Hexahedron;
}

/// The field at `p` if `p` lies in the cell of corners `v`; `along` as parametricCoordinates takes it, its
/// `start` left at the coordinates found.
template <int N>
UVR_HOST_DEVICE inline bool sampleIsoparametric(const MeshView &mesh, const uint32_t *v, uint64_t cell,
                                                Vec3f p, float &value, RaySolve *along = nullptr) {
  Vec3f r;
  const bool solved = parametricCoordinates<N>(mesh.points, v, p, r, along);
  if (along)
    along->start = r;
  if (!solved || !insideReference(r, N))
    return false;
  if (mesh.cellCentered) {
    value = mesh.values[cell];
    return true;
  }
  ShapeFunctions<N> s;
  evaluateShape(r, s);
  value = 0.f;
  for (int i = 0; i < N; ++i)
    value += s.value[i] * mesh.values[v[i]];
  return true;
}

/// The face of a hexahedron (cellFaces' order) that a point of parametric coordinates `r` lies furthest
/// beyond, and how far in `most` (negative inside).
UVR_HOST_DEVICE inline int hexFaceBeyond(Vec3f r, float &most) {
  int face = 0;
  most = -r.x;
  const auto consider = [&](float beyond, int f) {
    face = beyond > most ? f : face;
    most = maxf(beyond, most);
  };
  consider(r.x - 1.f, 1);
  consider(-r.y, 2);
  consider(r.y - 1.f, 3);
  consider(-r.z, 4);
  consider(r.z - 1.f, 5);
  return face;
}

/// The field at `p` if `p` lies in `cell`: interpolated for point data, the cell's own value for cell data.
UVR_HOST_DEVICE inline bool sampleCell(const MeshView &mesh, uint64_t cell, Vec3f p, float &value) {
  uint64_t local = cell;
  if (local < mesh.tetCount) {
    const uint32_t *v = mesh.tets + 4 * local;
    float w[4];
    if (!tetWeights(mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]], p, w))
      return false;
    value = mesh.cellCentered ? mesh.values[cell]
                              : w[0] * mesh.values[v[0]] + w[1] * mesh.values[v[1]] +
                                    w[2] * mesh.values[v[2]] + w[3] * mesh.values[v[3]];
    return true;
  }
  local -= mesh.tetCount;
  if (local < mesh.pyramidCount)
    return sampleIsoparametric<5>(mesh, mesh.pyramids + 5 * local, cell, p, value);
  local -= mesh.pyramidCount;
  if (local < mesh.wedgeCount)
    return sampleIsoparametric<6>(mesh, mesh.wedges + 6 * local, cell, p, value);
  local -= mesh.wedgeCount;
  return sampleIsoparametric<8>(mesh, mesh.hexes + 8 * local, cell, p, value);
}

/// Whether `p` lies in `cell`, as sampleCell decides it; reads no field.
UVR_HOST_DEVICE inline bool cellContains(const MeshView &mesh, uint64_t cell, Vec3f p) {
  uint64_t local = cell;
  if (local < mesh.tetCount) {
    const uint32_t *v = mesh.tets + 4 * local;
    float w[4];
    return tetWeights(mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]], p, w);
  }
  local -= mesh.tetCount;
  if (local < mesh.pyramidCount) {
    ShapeFunctions<5> s;
    return isoparametricWeights<5>(mesh.points, mesh.pyramids + 5 * local, p, s);
  }
  local -= mesh.pyramidCount;
  if (local < mesh.wedgeCount) {
    ShapeFunctions<6> s;
    return isoparametricWeights<6>(mesh.points, mesh.wedges + 6 * local, p, s);
  }
  local -= mesh.wedgeCount;
  ShapeFunctions<8> s;
  return isoparametricWeights<8>(mesh.points, mesh.hexes + 8 * local, p, s);
}

/// The corner points of `cell`, `count` of them.
UVR_HOST_DEVICE inline const uint32_t *cellCorners(const MeshView &mesh, uint64_t cell, int &count) {
  uint64_t local = cell;
  if (local < mesh.tetCount)
    return count = 4, mesh.tets + 4 * local;
  if ((local -= mesh.tetCount) < mesh.pyramidCount)
    return count = 5, mesh.pyramids + 5 * local;
  if ((local -= mesh.pyramidCount) < mesh.wedgeCount)
    return count = 6, mesh.wedges + 6 * local;
  local -= mesh.wedgeCount;
  return count = 8, mesh.hexes + 8 * local;
}

/// Calls `visit(point)` for each corner point of `cell`.
template <typename Visit>
UVR_HOST_DEVICE void forEachCellVertex(const MeshView &mesh, uint64_t cell, Visit &&visit) {
  int n;
  const uint32_t *v = cellCorners(mesh, cell, n);
  for (int i = 0; i < n; ++i)
    visit(v[i]);
}

/// Bounding box of one cell.
UVR_HOST_DEVICE inline Box3f cellBounds(const MeshView &mesh, uint64_t cell) {
  Box3f box;
  forEachCellVertex(mesh, cell, [&](uint32_t v) { box.extend(mesh.points[v]); });
  return box;
}

} // namespace uvr
