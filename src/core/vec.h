// Vector and box math shared by host and device code: the public value types and what the library adds.
#pragma once

#include "core/host_device.h"

#include <uvr/vec.h>

#include <cmath>
#include <cstdint>

namespace uvr {

// Plain comparisons compile to one instruction; fminf/fmaxf become library calls on x86 (NaN rules), which
// costs dearly in the per-cell and per-sample loops. Where NaN must be dropped, fminf/fmaxf are used instead.
UVR_HOST_DEVICE inline float minf(float a, float b) { return a < b ? a : b; }
UVR_HOST_DEVICE inline float maxf(float a, float b) { return a > b ? a : b; }
UVR_HOST_DEVICE inline float clampf(float v, float lo, float hi) { return minf(maxf(v, lo), hi); }

/// Four indices read at once, such as a tet's corners or neighbours: one 16-byte load on a GPU.
struct Index4 {
  uint32_t x, y, z, w;

  /// The four at `p`, which is 16-byte aligned on a GPU.
  UVR_HOST_DEVICE static Index4 load(const uint32_t *p) {
#ifdef __CUDA_ARCH__
    const uint4 q = *reinterpret_cast<const uint4 *>(p);
    return {q.x, q.y, q.z, q.w};
#else
    return {p[0], p[1], p[2], p[3]};
#endif
  }
  /// Selects, not an index: a GPU keeps an array indexed at run time in local memory.
  UVR_HOST_DEVICE uint32_t operator[](int i) const { return i < 2 ? (i == 0 ? x : y) : (i == 2 ? z : w); }
};

UVR_HOST_DEVICE inline Box3f intersection(const Box3f &a, const Box3f &b) {
  return {vmax(a.lower, b.lower), vmin(a.upper, b.upper)};
}

/// `box` grown by `pad` on every side.
UVR_HOST_DEVICE inline Box3f padded(const Box3f &box, float pad) {
  return {box.lower - Vec3f{pad, pad, pad}, box.upper + Vec3f{pad, pad, pad}};
}

/// Ray with a precomputed reciprocal direction for slab tests.
struct Ray {
  Vec3f origin;
  Vec3f direction;
  Vec3f invDirection;
  float tMax = INFINITY; ///< where the ray ends: nothing beyond is sampled

  UVR_HOST_DEVICE Vec3f at(float t) const { return origin + direction * t; }
};

UVR_HOST_DEVICE inline Ray makeRay(Vec3f origin, Vec3f direction) {
  return {origin, direction, {1.f / direction.x, 1.f / direction.y, 1.f / direction.z}};
}

/// Slab test; on a hit [t0, t1] is the overlap of the ray with the box, clipped to [tMin, tMax].
UVR_HOST_DEVICE inline bool intersectBox(const Ray &ray, const Box3f &box, float tMin, float tMax, float &t0,
                                         float &t1) {
  for (int axis = 0; axis < 3; ++axis) {
    const float tLower = (box.lower[axis] - ray.origin[axis]) * ray.invDirection[axis];
    const float tUpper = (box.upper[axis] - ray.origin[axis]) * ray.invDirection[axis];
    // A ray lying in a slab plane gives 0 * inf = NaN there; every comparison with NaN is false, so the
    // interval is left unchanged (the ray counts as inside the slab) without fminf's library call.
    const float tNear = tLower < tUpper ? tLower : tUpper;
    const float tFar = tLower < tUpper ? tUpper : tLower;
    tMin = tNear > tMin ? tNear : tMin;
    tMax = tFar < tMax ? tFar : tMax;
  }
  t0 = tMin;
  t1 = tMax;
  return tMin <= tMax;
}

} // namespace uvr
