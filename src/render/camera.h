// Ray generation for a camera (see <uvr/camera.h>).
#pragma once

#include "core/host_device.h"
#include "core/vec.h"

#include <uvr/camera.h>

#include <cmath>

namespace uvr {

/// Per-pixel ray generation, precomputed once per frame.
struct CameraView {
  Vec3f eye;
  Vec3f forward;
  Vec3f right; ///< spans half the image width at unit distance
  Vec3f up;    ///< spans half the image height at unit distance
  int width = 0, height = 0;
  /// Null, or where each pixel's ray ends, row-major (FrameSettings::rayLimits); on the backend's side.
  const float *limits = nullptr;

  /// Image coordinates in [-1, 1] of the centre of pixel column x and of pixel row y.
  UVR_HOST_DEVICE float imageU(int x) const { return 2.f * (float(x) + 0.5f) / float(width) - 1.f; }
  UVR_HOST_DEVICE float imageV(int y) const { return 1.f - 2.f * (float(y) + 0.5f) / float(height); }

  UVR_HOST_DEVICE Ray ray(int x, int y) const {
    Ray ray = makeRay(eye, normalize(forward + right * imageU(x) + up * imageV(y)));
    // Rays past the frame's edge (the CPU's look-ahead to the next row) have no limit of their own.
    if (limits && x >= 0 && x < width && y >= 0 && y < height)
      ray.tMax = limits[size_t(y) * size_t(width) + size_t(x)];
    return ray;
  }
};

inline CameraView makeCameraView(const Camera &camera, int width, int height, const float *limits = nullptr) {
  CameraView view;
  view.eye = camera.eye;
  view.forward = normalize(camera.at - camera.eye);
  const Vec3f right = normalize(cross(view.forward, camera.up));
  const Vec3f up = cross(right, view.forward);
  const float halfHeight = std::tan(0.5f * camera.fovy * float(M_PI) / 180.f);
  view.right = right * (halfHeight * float(width) / float(height));
  view.up = up * halfHeight;
  view.width = width;
  view.height = height;
  view.limits = limits;
  return view;
}

} // namespace uvr
