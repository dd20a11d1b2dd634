// Where each pixel's ray crosses the boundary of a tet mesh first and last, found per frame by projecting
// the boundary faces (tet faces with no neighbour) onto the image and testing each against the rays of the
// pixels it covers. Before its first crossing and after its last, a ray that starts outside the mesh meets
// no cell: the skipping modes march neither stretch, and a ray that crosses no face is done at once. Faces
// are tested against the very rays the integrator shoots, with a tolerance at their edges, so a ray through
// an edge or a corner shared by faces crosses at least one of them.
#pragma once

#include "accel/seed_grid.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/mesh_view.h"
#include "render/camera.h"

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace uvr {

/// Along one ray: its first and last crossing with the boundary, and the face crossed first. The default
/// says nothing is known.
struct BoundaryCrossings {
  float first = -INFINITY, last = INFINITY; ///< first = INFINITY: the ray crosses no face
  uint32_t face = kNoCell;                  ///< 4 * tet + i
};

/// Where `ray` crosses the plane of triangle abc, if it does so within the triangle or within a relative
/// 1e-4 of its edges; INFINITY otherwise, and for a ray parallel to the plane.
UVR_HOST_DEVICE inline float rayCrossesTriangle(const Ray &ray, Vec3f a, Vec3f b, Vec3f c) {
  const Vec3f e1 = b - a, e2 = c - a;
  const Vec3f pv = cross(ray.direction, e2);
  const float det = dot(e1, pv);
  if (det == 0.f)
    return INFINITY;
  const float inv = 1.f / det;
  const Vec3f tv = ray.origin - a;
  const float u = dot(tv, pv) * inv;
  const Vec3f qv = cross(tv, e1);
  const float v = dot(ray.direction, qv) * inv;
  constexpr float kEdgeTolerance = 1e-4f;
  if (!(u >= -kEdgeTolerance && v >= -kEdgeTolerance && u + v <= 1.f + kEdgeTolerance))
    return INFINITY;
  return dot(e2, qv) * inv;
}

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
/// face: the first crossing of a pixel is the least word, whatever order the faces arrive in.
UVR_HOST_DEVICE inline uint64_t crossingKey(float t, uint32_t face) {
  return (uint64_t(floatBits(t)) << 32) | face;
}
/// Per pixel, before any face is seen: the least key is the first crossing, the largest bits the last.
constexpr uint64_t kNoCrossing = ~uint64_t(0);
constexpr uint32_t kNoLastCrossing = 0; // the bits of +0

/// What a pixel's least key and largest bits say about its ray.
UVR_HOST_DEVICE inline BoundaryCrossings pixelCrossings(uint64_t firstKey, uint32_t lastBits) {
  BoundaryCrossings crossings;
  crossings.first = firstKey == kNoCrossing ? INFINITY : bitsFloat(uint32_t(firstKey >> 32));
  crossings.last = bitsFloat(lastBits);
  crossings.face = firstKey == kNoCrossing ? kNoCell : uint32_t(firstKey);
  return crossings;
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

/// Calls `visit(x, y, t)` for each pixel whose ray crosses boundary face `face` at t > 0: the pixels whose
/// centres lie in the face's projected box, widened by a twentieth of a pixel for rounding and the edge
/// tolerance (a relative 1e-4 of the face, far less for all but faces spanning hundreds of pixels).
template <typename Visit>
UVR_HOST_DEVICE void forEachPixelCrossing(const MeshView &mesh, uint32_t face, const CameraView &camera,
                                          Visit &&visit) {
  Vec3f corners[3];
  tetFaceCorners(mesh, face, corners[0], corners[1], corners[2]);
  const float rightScale = 1.f / dot(camera.right, camera.right), upScale = 1.f / dot(camera.up, camera.up);
  float xLow = INFINITY, xHigh = -INFINITY, yLow = INFINITY, yHigh = -INFINITY;
  for (const Vec3f &p : corners) {
    // Where p projects, in pixels whose centres lie at whole numbers.
    const Vec3f d = p - camera.eye;
    const float depth = dot(d, camera.forward);
    const float u = dot(d, camera.right) * rightScale / depth, v = dot(d, camera.up) * upScale / depth;
    const float x = 0.5f * (u + 1.f) * float(camera.width) - 0.5f,
                y = 0.5f * (1.f - v) * float(camera.height) - 0.5f;
    xLow = fminf(xLow, x), xHigh = fmaxf(xHigh, x), yLow = fminf(yLow, y), yHigh = fmaxf(yHigh, y);
  }
  constexpr float kMargin = 0.05f;
  const int x0 = int(fmaxf(ceilf(xLow - kMargin), 0.f)),
            x1 = int(fminf(floorf(xHigh + kMargin), float(camera.width - 1)));
  const int y0 = int(fmaxf(ceilf(yLow - kMargin), 0.f)),
            y1 = int(fminf(floorf(yHigh + kMargin), float(camera.height - 1)));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const float t = rayCrossesTriangle(camera.ray(x, y), corners[0], corners[1], corners[2]);
      if (t > 0.f && t < INFINITY)
        visit(x, y, t);
    }
}

/// Per pixel of `camera`'s image, the least crossing key over all `faces` (kNoCrossing where none) into
/// `first`, and the bits of the last crossing (kNoLastCrossing where none) into `last`; with all cores.
void findBoundaryCrossings(const MeshView &mesh, std::span<const uint32_t> faces, const CameraView &camera,
                           std::vector<uint64_t> &first, std::vector<uint32_t> &last);

} // namespace uvr
