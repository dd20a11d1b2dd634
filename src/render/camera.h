// A pinhole camera as ParaView describes one: eye, focal point, view-up and vertical view angle.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"

#include <cmath>

namespace uvr {

struct Camera {
  Vec3f eye{0.f, 0.f, 1.f};
  Vec3f at{0.f, 0.f, 0.f};
  Vec3f up{0.f, 1.f, 0.f};
  float fovy = 30.f; ///< degrees, vertical
};

/// ParaView's reset camera (vtkRenderer::ResetCamera): looking down -z with +y up, at a distance where the
/// bounding sphere of `bounds` fills the vertical view angle, or the horizontal one when the image is taller
/// than wide (`aspect` = width / height < 1).
inline Camera frameBounds(const Box3f &bounds, float fovy = 30.f, float aspect = 1.f) {
  Camera camera;
  camera.at = bounds.center();
  const float radius = 0.5f * length(bounds.size());
  float halfAngle = 0.5f * fovy * float(M_PI) / 180.f;
  if (aspect < 1.f)
    halfAngle = std::atan(std::tan(halfAngle) * aspect);
  const float distance = radius / std::sin(halfAngle);
  camera.eye = camera.at + Vec3f{0.f, 0.f, distance};
  camera.up = {0.f, 1.f, 0.f};
  camera.fovy = fovy;
  return camera;
}

/// Per-pixel ray generation, precomputed once per frame.
struct CameraView {
  Vec3f eye;
  Vec3f forward;
  Vec3f right; ///< spans half the image width at unit distance
  Vec3f up;    ///< spans half the image height at unit distance
  int width = 0, height = 0;

  UVR_HOST_DEVICE Ray ray(int x, int y) const {
    const float u = 2.f * (float(x) + 0.5f) / float(width) - 1.f;
    const float v = 1.f - 2.f * (float(y) + 0.5f) / float(height);
    return makeRay(eye, normalize(forward + right * u + up * v));
  }
};

inline CameraView makeCameraView(const Camera &camera, int width, int height) {
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
  return view;
}

} // namespace uvr
