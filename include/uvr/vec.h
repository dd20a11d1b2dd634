// Small vectors and boxes: plain values, usable from host and CUDA device code alike.
#pragma once

#include <uvr/host_device.h>

#include <cmath>

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
// Plain comparisons, which compile to one instruction each (fminf and fmaxf are library calls on x86): a NaN
// in `b` is taken, one in `a` is not.
UVR_HOST_DEVICE inline Vec3f vmin(Vec3f a, Vec3f b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
UVR_HOST_DEVICE inline Vec3f vmax(Vec3f a, Vec3f b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

/// Colour and opacity, or any four floats.
struct Vec4f {
  float x = 0.f, y = 0.f, z = 0.f, w = 0.f;
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

} // namespace uvr
