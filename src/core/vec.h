// Small vector and box math shared by host and device code.
#pragma once

#include "core/host_device.h"

#include <cmath>
#include <cstdint>

namespace uvr {

struct Vec3f {
  float x = 0.f, y = 0.f, z = 0.f;

  UVR_HOST_DEVICE float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  UVR_HOST_DEVICE float &operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

UVR_HOST_DEVICE inline Vec3f operator+(Vec3f a, Vec3f b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
UVR_HOST_DEVICE inline Vec3f operator-(Vec3f a, Vec3f b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
UVR_HOST_DEVICE inline Vec3f operator*(Vec3f a, float s) { return {a.x * s, a.y * s, a.z * s}; }
UVR_HOST_DEVICE inline Vec3f operator*(float s, Vec3f a) { return a * s; }
UVR_HOST_DEVICE inline Vec3f operator/(Vec3f a, float s) { return a * (1.f / s); }
UVR_HOST_DEVICE inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
UVR_HOST_DEVICE inline Vec3f cross(Vec3f a, Vec3f b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
UVR_HOST_DEVICE inline float length(Vec3f a) { return sqrtf(dot(a, a)); }
UVR_HOST_DEVICE inline Vec3f normalize(Vec3f a) { return a / length(a); }
// Plain comparisons compile to one instruction; fminf/fmaxf become library calls on x86 (NaN rules), which
// costs dearly in the per-cell and per-sample loops. Where NaN must be dropped, fminf/fmaxf are used instead.
UVR_HOST_DEVICE inline float minf(float a, float b) { return a < b ? a : b; }
UVR_HOST_DEVICE inline float maxf(float a, float b) { return a > b ? a : b; }
UVR_HOST_DEVICE inline float clampf(float v, float lo, float hi) { return minf(maxf(v, lo), hi); }
UVR_HOST_DEVICE inline Vec3f vmin(Vec3f a, Vec3f b) {
  return {minf(a.x, b.x), minf(a.y, b.y), minf(a.z, b.z)};
}
UVR_HOST_DEVICE inline Vec3f vmax(Vec3f a, Vec3f b) {
  return {maxf(a.x, b.x), maxf(a.y, b.y), maxf(a.z, b.z)};
}

struct Vec4f {
  float x = 0.f, y = 0.f, z = 0.f, w = 0.f;
};

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

/// Axis-aligned box; empty when lower > upper on any axis.
struct Box3f {
  Vec3f lower{INFINITY, INFINITY, INFINITY};
  Vec3f upper{-INFINITY, -INFINITY, -INFINITY};

  UVR_HOST_DEVICE bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
  UVR_HOST_DEVICE void extend(Vec3f p) {
    lower = vmin(lower, p);
    upper = vmax(upper, p);
  }
  UVR_HOST_DEVICE void extend(const Box3f &b) {
    lower = vmin(lower, b.lower);
    upper = vmax(upper, b.upper);
  }
  UVR_HOST_DEVICE Vec3f center() const { return (lower + upper) * 0.5f; }
  UVR_HOST_DEVICE Vec3f size() const { return upper - lower; }
  UVR_HOST_DEVICE bool contains(Vec3f p) const {
    return p.x >= lower.x && p.y >= lower.y && p.z >= lower.z && p.x <= upper.x && p.y <= upper.y &&
           p.z <= upper.z;
  }
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
