// A pinhole camera as ParaView describes one: eye, focal point, view-up and vertical view angle.
#pragma once

#include <uvr/vec.h>

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
  constexpr float kPi = 3.14159265358979323846f;
  Camera camera;
  camera.at = bounds.center();
  const float radius = 0.5f * length(bounds.size());
  float halfAngle = 0.5f * fovy * kPi / 180.f;
  if (aspect < 1.f)
    halfAngle = std::atan(std::tan(halfAngle) * aspect);
  const float distance = radius / std::sin(halfAngle);
  camera.eye = camera.at + Vec3f{0.f, 0.f, distance};
  camera.up = {0.f, 1.f, 0.f};
  camera.fovy = fovy;
  return camera;
}

} // namespace uvr
