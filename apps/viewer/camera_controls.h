// Orbit, pan and zoom of a ParaView-style camera (eye, focal point, view-up), for mouse drags and scripts.
#pragma once

#include <uvr/camera.h>

#include <cmath>

namespace uvr {

/// `v` rotated by `degrees` about the unit `axis` (Rodrigues).
inline Vec3f rotate(Vec3f v, Vec3f axis, float degrees) {
  const float a = degrees * float(M_PI) / 180.f;
  const float c = std::cos(a), s = std::sin(a);
  return v * c + cross(axis, v) * s + axis * (dot(axis, v) * (1.f - c));
}

/// Turns the eye about the focal point: `azimuth` degrees about the view-up, then `elevation` degrees about
/// the camera's right axis (ParaView's Azimuth and Elevation, with the view-up kept orthogonal).
inline Camera orbit(Camera camera, float azimuth, float elevation) {
  const Vec3f up = normalize(camera.up);
  Vec3f offset = rotate(camera.eye - camera.at, up, azimuth);
  const Vec3f forward = normalize(offset * -1.f);
  const Vec3f right = normalize(cross(forward, up));
  const Vec3f trueUp = cross(right, forward);
  offset = rotate(offset, right, elevation);
  camera.eye = camera.at + offset;
  camera.up = rotate(trueUp, right, elevation);
  return camera;
}

/// Moves eye and focal point together across the view by (dx, dy) view heights at the focal distance
/// (positive dx: the scene moves right, positive dy: up).
inline Camera pan(Camera camera, float dx, float dy) {
  const Vec3f offset = camera.at - camera.eye;
  const Vec3f forward = normalize(offset);
  const Vec3f right = normalize(cross(forward, camera.up));
  const Vec3f up = cross(right, forward);
  const float viewHeight = 2.f * length(offset) * std::tan(0.5f * camera.fovy * float(M_PI) / 180.f);
  const Vec3f shift = (right * -dx + up * -dy) * viewHeight;
  camera.eye = camera.eye + shift;
  camera.at = camera.at + shift;
  return camera;
}

/// Moves the eye towards the focal point, dividing the distance by `factor` (> 1 zooms in).
inline Camera zoom(Camera camera, float factor) {
  camera.eye = camera.at + (camera.eye - camera.at) * (1.f / factor);
  return camera;
}

} // namespace uvr
