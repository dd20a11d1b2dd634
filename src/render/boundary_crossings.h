// Where each pixel's ray crosses the boundary of a mesh, found per frame by projecting the boundary faces
// (cell faces with no cell across; a quadrilateral as two triangles) onto the image and testing each against
// the rays of the pixels it covers. Before its first crossing, after its last, and between a crossing out of
// the mesh and the next one back in, a ray that starts outside the mesh meets no cell: the skipping modes
// march none of those stretches, a ray that crosses no face is done at once, and the march past a gap starts
// at the cell it enters by. Faces are tested against the very rays the integrator shoots, with a tolerance
// at their edges, so a ray through an edge or a corner shared by faces crosses at least one of them.
#pragma once

#include "accel/seed_grid.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell_neighbors.h"
#include "mesh/mesh_view.h"
#include "render/camera.h"

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace uvr {

/// Along one ray: its first and last crossing with the boundary, the face crossed first, and every crossing
/// in order of t (see crossingKey). The default says nothing is known.
struct BoundaryCrossings {
  float first = -INFINITY, last = INFINITY; ///< first = INFINITY: the ray crosses no face
  uint32_t face = kNoCell;                  ///< numbered as boundaryFaceBits says
  const uint64_t *keys = nullptr;
  uint32_t count = 0;

  /// Whether the ray is known to cross no face: it misses the mesh.
  UVR_HOST_DEVICE bool none() const { return first == INFINITY; }
};

UVR_HOST_DEVICE inline uint32_t floatBits(float f) {
  uint32_t bits;
  memcpy(&bits, &f, sizeof bits);
  return bits;
}
UVR_HOST_DEVICE inline float bitsFloat(uint32_t bits) {
  float f;
  memcpy(&f, &bits, sizeof f);
  return f;
}

/// A crossing as one word whose order is that of t (positive, so its bits order as it does), then of the
/// face: sorting a pixel's words orders its crossings along the ray, whatever order the faces arrive in. The
/// lowest bit of t's says whether the ray leaves the mesh there (a change of t by one unit in the last
/// place).
UVR_HOST_DEVICE inline uint64_t crossingKey(float t, uint32_t face, bool exits) {
  return (uint64_t((floatBits(t) & ~1u) | (exits ? 1u : 0u)) << 32) | face;
}
UVR_HOST_DEVICE inline float crossingT(uint64_t key) { return bitsFloat(uint32_t(key >> 32)); }
UVR_HOST_DEVICE inline uint32_t crossingFace(uint64_t key) { return uint32_t(key); }
UVR_HOST_DEVICE inline bool crossingExits(uint64_t key) { return (key >> 32) & 1u; }

/// What pixel `pixel`'s crossings, keys[start[pixel]] to keys[start[pixel + 1]] in order, say about its ray.
UVR_HOST_DEVICE inline BoundaryCrossings pixelCrossings(const uint64_t *start, const uint64_t *keys,
                                                        uint64_t pixel) {
  BoundaryCrossings crossings;
  crossings.keys = keys + start[pixel];
  crossings.count = uint32_t(start[pixel + 1] - start[pixel]);
  if (crossings.count == 0) {
    crossings.first = INFINITY;
    return crossings;
  }
  crossings.first = crossingT(crossings.keys[0]);
  crossings.last = crossingT(crossings.keys[crossings.count - 1]);
  crossings.face = crossingFace(crossings.keys[0]);
  return crossings;
}

/// Where a march stands among its ray's crossings (see afterGap): the first crossing not yet passed, and what
/// the march needs of it, so that most samples read none.
struct CrossingCursor {
  uint32_t next = 0;
  float nextT = -INFINITY; ///< t of crossing `next`, INFINITY past the last; -INFINITY before the first look
  bool inGap = false;      ///< whether crossing next - 1 leaves the mesh and crossing `next` enters it again
  /// Crossings into the mesh less those out of it, before `next` (those repeated at an edge once): a gap
  /// needs it at 0. Faces that no cell across was found for (pieces whose points were not joined) come in
  /// pairs, one in and one out, in either order where the two round differently, and are no gap.
  int depth = 0;
  /// The last gap's ends, once the march has met it: where the ray last left the mesh and came back in.
  float gapExit = -INFINITY, gapEntry = -INFINITY;
};

/// Where the ray leaves the gap in the mesh that holds t, if it lies in one: the crossing after the last one
/// at or before t, where the ray goes out of the mesh and that one back in, and t lies farther than `margin`
/// from both; else t. `cursor` is left at the first crossing past t: along a ray, t only grows. `entered` is
/// set to the face the ray comes back in by: of a gap that holds t, or of the last crossing passed since the
/// previous call where that one leads into the mesh (a gap between two samples); else kNoCell.
UVR_HOST_DEVICE inline float afterGap(const BoundaryCrossings &crossings, float t, float margin,
                                      CrossingCursor &cursor, uint32_t &entered) {
  entered = kNoCell;
  if (t < cursor.nextT && !cursor.inGap)
    return t;
  uint32_t next = cursor.next;
  for (; next < crossings.count && crossingT(crossings.keys[next]) <= t; ++next) {
    const uint64_t key = crossings.keys[next];
    const bool exits = crossingExits(key);
    // A ray through an edge or a corner crosses each face there, the same way: once.
    const bool repeated = next > 0 && crossingExits(crossings.keys[next - 1]) == exits &&
                          crossingT(key) - crossingT(crossings.keys[next - 1]) <= margin;
    cursor.depth += repeated ? 0 : exits ? -1 : 1;
    entered = exits ? kNoCell : crossingFace(key);
    if (repeated)
      continue;
    if (exits)
      cursor.gapExit = crossingT(key);
    else
      cursor.gapEntry = crossingT(key);
  }
  cursor.next = next;
  cursor.nextT = next < crossings.count ? crossingT(crossings.keys[next]) : INFINITY;
  // Before the first crossing or after the last, the march's interval leaves the ray out.
  cursor.inGap = next > 0 && next < crossings.count && crossingExits(crossings.keys[next - 1]) &&
                 !crossingExits(crossings.keys[next]) && cursor.depth <= 0;
  if (!cursor.inGap)
    return t;
  const float before = crossingT(crossings.keys[next - 1]);
  if (!(t > before + margin) || !(t < cursor.nextT - margin))
    return t;
  entered = crossingFace(crossings.keys[next]);
  cursor.gapExit = before;
  cursor.gapEntry = cursor.nextT;
  return cursor.nextT - margin;
}

/// Whether the crossings describe the frame: the eye lies outside `meshBox` (so every ray starts outside
/// the mesh) and the whole box in front of it (so every face projects onto the image plane).
UVR_HOST_DEVICE inline bool crossingsApply(const CameraView &camera, const Box3f &meshBox) {
  if (meshBox.contains(camera.eye))
    return false;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3f p = {corner & 1 ? meshBox.upper.x : meshBox.lower.x,
                     corner & 2 ? meshBox.upper.y : meshBox.lower.y,
                     corner & 4 ? meshBox.upper.z : meshBox.lower.z};
    if (!(dot(p - camera.eye, camera.forward) > 0.f))
      return false;
  }
  return true;
}

/// The pixels whose centres lie in the projected box of `count` points, widened by a twentieth of a pixel for
/// rounding and the edge tolerance of the tests below: columns x0 to x1, rows y0 to y1 (empty where x1 < x0).
UVR_HOST_DEVICE inline void pixelsCovered(const Vec3f *corners, int count, const CameraView &camera, int &x0,
                                          int &x1, int &y0, int &y1) {
  const float rightScale = 1.f / dot(camera.right, camera.right), upScale = 1.f / dot(camera.up, camera.up);
  float xLow = INFINITY, xHigh = -INFINITY, yLow = INFINITY, yHigh = -INFINITY;
  for (int i = 0; i < count; ++i) {
    const Vec3f &p = corners[i];
    // Where p projects, in pixels whose centres lie at whole numbers.
    const Vec3f d = p - camera.eye;
    const float depth = dot(d, camera.forward);
    const float u = dot(d, camera.right) * rightScale / depth, v = dot(d, camera.up) * upScale / depth;
    const float x = 0.5f * (u + 1.f) * float(camera.width) - 0.5f,
                y = 0.5f * (1.f - v) * float(camera.height) - 0.5f;
    // Comparisons that drop a NaN first argument, as fminf and fmaxf do, without their library calls.
    xLow = minf(x, xLow), xHigh = maxf(x, xHigh), yLow = minf(y, yLow), yHigh = maxf(y, yHigh);
  }
  constexpr float kMargin = 0.05f;
  x0 = int(maxf(ceilf(xLow - kMargin), 0.f)),
  x1 = int(minf(floorf(xHigh + kMargin), float(camera.width - 1)));
  y0 = int(maxf(ceilf(yLow - kMargin), 0.f)),
  y1 = int(minf(floorf(yHigh + kMargin), float(camera.height - 1)));
}

/// Calls `visit(pixel, key)` for each pixel whose ray crosses triangle `corners` of boundary face `face` at
/// t > 0 (`key` being crossingKey's; `inner` lies on the mesh's side of it): the pixels whose centres lie in
/// the triangle's projected box, widened by a twentieth of a pixel for rounding and the edge tolerance (a
/// relative 1e-4 of the triangle, far less for all but triangles spanning hundreds of pixels).
template <typename Visit>
UVR_HOST_DEVICE void forEachTriangleCrossing(const Vec3f corners[3], Vec3f inner, uint32_t face,
                                             const CameraView &camera, Visit &&visit) {
  const Vec3f e1 = corners[1] - corners[0], e2 = corners[2] - corners[0], toEye = camera.eye - corners[0];
  // Every ray from the eye that crosses the triangle's plane runs the same way along its normal: out of the
  // mesh where the eye lies on the inner side.
  const Vec3f normal = cross(e1, e2);
  const bool exits = (dot(normal, inner - corners[0]) < 0.f) == (dot(normal, toEye) < 0.f);
  int x0, x1, y0, y1;
  pixelsCovered(corners, 3, camera, x0, x1, y0, y1);
  // Moeller and Trumbore's test, along the unnormalised direction D = forward + u right + v up of the ray
  // through the pixel at image coordinates (u, v): its determinant and both numerators are dot products
  // with D, so linear in u and v, and t along D is the same numerator over the determinant for every pixel.
  // The rays that meet the triangle's plane at t > 0 share the sign of that numerator: with it folded into
  // the determinant and the others, those rays' determinants are positive and the barycentric tests take no
  // division, which is left for the few rays that pass. A crossing is kept within a relative 1e-4 of the
  // triangle's edges, and its t is scaled to the unit ray.
  const Vec3f determinant = cross(e2, e1), first = cross(e2, toEye), second = cross(toEye, e1);
  const float along = dot(e2, second);
  if (!(along != 0.f)) // the eye lies in the triangle's plane
    return;
  const float sign = along < 0.f ? -1.f : 1.f;
  auto linear = [&](const Vec3f &n, float &base, float &perU, float &perV) {
    base = sign * dot(camera.forward, n), perU = sign * dot(camera.right, n), perV = sign * dot(camera.up, n);
  };
  float det0, detU, detV, first0, firstU, firstV, second0, secondU, secondV;
  linear(determinant, det0, detU, detV);
  linear(first, first0, firstU, firstV);
  linear(second, second0, secondU, secondV);
  constexpr float kEdgeTolerance = 1e-4f;
  const float distance = fabsf(along);
#ifdef __CUDA_ARCH__
  constexpr int kRowChunk = 1; // a GPU thread would keep the chunk's arrays in memory: pixel by pixel
#else
  constexpr int kRowChunk = 64;
#endif
  for (int y = y0; y <= y1; ++y) {
    const float v = camera.imageV(y);
    const float detRow = det0 + v * detV, firstRow = first0 + v * firstV, secondRow = second0 + v * secondV;
    // On the host, the row's pixels are tested 64 at a time, with no branch, which leaves the loop to
    // vectorise: which pixels pass is unpredictable.
    for (int xs = x0; xs <= x1; xs += kRowChunk) {
      const int count = x1 - xs + 1 < kRowChunk ? x1 - xs + 1 : kRowChunk;
      float dets[kRowChunk];
      bool hits[kRowChunk];
      for (int i = 0; i < count; ++i) {
        const float u = camera.imageU(xs + i);
        const float det = detRow + u * detU, a = firstRow + u * firstU, b = secondRow + u * secondU;
        const float slack = kEdgeTolerance * det;
        hits[i] = (det > 0.f) & (a >= -slack) & (b >= -slack) & (a + b <= det + slack);
        dets[i] = det;
      }
      for (int i = 0; i < count; ++i) {
        if (!hits[i])
          continue;
        const int x = xs + i;
        const float u = camera.imageU(x);
        const Vec3f direction = camera.forward + camera.right * u + camera.up * v;
        const float t = distance / dets[i] * sqrtf(dot(direction, direction));
        if (t > 0.f && t < INFINITY)
          visit(uint64_t(y) * uint64_t(camera.width) + uint64_t(x), crossingKey(t, face, exits));
      }
    }
  }
}

/// Calls `visit(pixel, key)` for each crossing of a pixel's ray with the bilinear patch through quadrilateral
/// `corners` (in order around it) of boundary face `face`, at t > 0: the face of a hexahedron, wedge or
/// pyramid exactly as its cell's trilinear map bounds it, which a bent face's two triangles would not be.
/// A ray may cross it twice, each time either way: the way is the patch's normal there against its
/// orientation, found at its centre against `inner`. Reshetov's ray/patch test (Ray Tracing Gems, 2019):
/// a quadratic in the patch's u, then v and t from the closest points of two lines; crossings are kept
/// within a relative 1e-4 of its edges. The patch lies within its corners' hull, whose projected box
/// bounds the pixels tested.
template <typename Visit>
UVR_HOST_DEVICE void forEachQuadCrossing(const Vec3f corners[4], Vec3f inner, uint32_t face,
                                         const CameraView &camera, Visit &&visit) {
  const Vec3f q00 = corners[0], q10 = corners[1], q11 = corners[2], q01 = corners[3];
  const Vec3f e10 = q10 - q00, e11 = q11 - q10, e00 = q01 - q00;
  // The patch's normal at (u, v) is du x dv: at its centre, which way is out of the cell.
  const Vec3f centreNormal = cross((e10 + (q11 - q01)) * 0.5f, (e00 + e11) * 0.5f);
  const bool outward = dot(centreNormal, (q00 + q10 + q11 + q01) * 0.25f - inner) > 0.f;
  const Vec3f qn = cross(e10, q01 - q11);
  const Vec3f a00 = q00 - camera.eye, a10 = q10 - camera.eye;
  constexpr float kEdgeTolerance = 1e-4f;
  int x0, x1, y0, y1;
  pixelsCovered(corners, 4, camera, x0, x1, y0, y1);
  for (int y = y0; y <= y1; ++y) {
    const float v = camera.imageV(y);
    for (int x = x0; x <= x1; ++x) {
      const Vec3f d = camera.forward + camera.right * camera.imageU(x) + camera.up * v;
      const float a = dot(cross(a00, d), e00), c = dot(qn, d);
      const float b = dot(cross(a10, d), e11) - (a + c);
      const float discriminant = b * b - 4.f * a * c;
      if (!(discriminant >= 0.f))
        continue;
      const float root = sqrtf(discriminant);
      float us[2];
      if (c == 0.f) { // a trapezoid: one root
        us[0] = b != 0.f ? -a / b : -1.f;
        us[1] = -1.f;
      } else {
        const float q = -0.5f * (b + copysignf(root, b));
        us[0] = q / c;
        us[1] = q != 0.f ? a / q : -1.f;
      }
      const float length = sqrtf(dot(d, d));
      for (int i = 0; i < 2; ++i) {
        const float u = us[i];
        if (!(u >= -kEdgeTolerance && u <= 1.f + kEdgeTolerance))
          continue;
        // The closest points of the ray and the patch's line at u, from pa along pb.
        const Vec3f pa = a00 + (a10 - a00) * u, pb = e00 + (e11 - e00) * u;
        const Vec3f n = cross(d, pb);
        const float squared = dot(n, n);
        const Vec3f m = cross(n, pa);
        const float t = dot(m, pb), w = dot(m, d);
        if (!(squared > 0.f) || !(w >= -kEdgeTolerance * squared && w <= (1.f + kEdgeTolerance) * squared))
          continue;
        const float tUnit = t / squared * length;
        if (!(tUnit > 0.f && tUnit < INFINITY))
          continue;
        const float vAt = w / squared;
        const Vec3f du = e10 + ((q11 - q01) - e10) * vAt;
        const bool exits = (dot(cross(du, pb), d) > 0.f) == outward;
        visit(uint64_t(y) * uint64_t(camera.width) + uint64_t(x), crossingKey(tUnit, face, exits));
      }
    }
  }
}

/// Calls `visit(pixel, key)` for each pixel whose ray crosses boundary face `face` (numbered as
/// boundaryFaceBits says) at t > 0.
template <typename Visit>
UVR_HOST_DEVICE void forEachPixelCrossing(const MeshView &mesh, uint32_t face, const CameraView &camera,
                                          Visit &&visit) {
  Vec3f corners[4], inner;
  if (boundaryFaceCorners(mesh, face, corners, inner) == 3)
    forEachTriangleCrossing(corners, inner, face, camera, visit);
  else
    forEachQuadCrossing(corners, inner, face, camera, visit);
}

/// Every crossing of each pixel's ray of `camera`'s image with `faces`: pixel p's keys are keys[start[p]]
/// to keys[start[p + 1]], ordered by t (start has two entries more than the image has pixels, the last
/// being the total); with all cores.
void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &start, std::vector<uint64_t> &keys);

} // namespace uvr
