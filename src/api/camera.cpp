#include <uvr/camera.h>
#include <uvr/error.h>

#include "render/camera.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace uvr {

namespace {

struct NamedView {
  const char *name;
  Vec3f from; ///< direction from the focal point to the eye
  Vec3f up;
};

// ParaView's view-direction buttons, named by the side the camera looks from.
constexpr NamedView kViews[] = {
    {"+x", {1.f, 0.f, 0.f}, {0.f, 0.f, 1.f}},  {"-x", {-1.f, 0.f, 0.f}, {0.f, 0.f, 1.f}},
    {"+y", {0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}},  {"-y", {0.f, -1.f, 0.f}, {0.f, 0.f, 1.f}},
    {"+z", {0.f, 0.f, 1.f}, {0.f, 1.f, 0.f}},  {"-z", {0.f, 0.f, -1.f}, {0.f, 1.f, 0.f}},
    {"iso", {1.f, 1.f, 1.f}, {0.f, 1.f, 0.f}},
};

bool finite(Vec3f v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string text(Vec3f v) {
  std::ostringstream out;
  out << v.x << ',' << v.y << ',' << v.z;
  return out.str();
}

} // namespace

PixelBox boxPixels(const Camera &camera, int width, int height, const Box3f &box) {
  const PixelBox whole{0, width, 0, height};
  const CameraView view = makeCameraView(camera, width, height);
  // A ray's direction is forward + right * u + up * v, with u and v in [-1, 1] across the image.
  const float rightScale = 1.f / dot(view.right, view.right), upScale = 1.f / dot(view.up, view.up);
  float uLow = INFINITY, uHigh = -INFINITY, vLow = INFINITY, vHigh = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3f p{corner & 1 ? box.upper.x : box.lower.x, corner & 2 ? box.upper.y : box.lower.y,
                  corner & 4 ? box.upper.z : box.lower.z};
    const Vec3f d = p - view.eye;
    const float depth = dot(d, view.forward);
    if (!(depth > 0.f))
      return whole;
    const float u = dot(d, view.right) * rightScale / depth, v = dot(d, view.up) * upScale / depth;
    uLow = std::min(uLow, u), uHigh = std::max(uHigh, u);
    vLow = std::min(vLow, v), vHigh = std::max(vHigh, v);
  }
  // The pixel whose centre lies at u is (u + 1) * width / 2 - 0.5 (CameraView::imageU); rows count down.
  const auto clamped = [](float at, int size) { return int(std::clamp(at, 0.f, float(size))); };
  return {clamped(std::floor(0.5f * (uLow + 1.f) * float(width)) - 1.f, width),
          clamped(std::ceil(0.5f * (uHigh + 1.f) * float(width)) + 1.f, width),
          clamped(std::floor(0.5f * (1.f - vHigh) * float(height)) - 1.f, height),
          clamped(std::ceil(0.5f * (1.f - vLow) * float(height)) + 1.f, height)};
}

std::vector<std::string> cameraViewNames() {
  std::vector<std::string> names;
  for (const NamedView &view : kViews)
    names.emplace_back(view.name);
  return names;
}

Camera frameBounds(const Box3f &bounds, const std::string &view, float fovy, float aspect) {
  if (!(aspect > 0.f) || !std::isfinite(aspect))
    throw Error("the image aspect must be positive");
  if (!(fovy > 0.f && fovy < 180.f))
    validateCamera(Camera{{0.f, 0.f, 1.f}, {0.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, fovy}); // throws, naming fovy
  for (const NamedView &named : kViews) {
    if (view != named.name)
      continue;
    Camera camera = frameBounds(bounds, fovy, aspect); // from +z, as the reset camera
    if (view != "+z") {
      const float distance = length(camera.eye - camera.at);
      camera.eye = camera.at + normalize(named.from) * distance;
      camera.up = named.up;
    }
    validateCamera(camera);
    return camera;
  }
  std::string names;
  for (const NamedView &named : kViews)
    names += std::string(names.empty() ? "" : ", ") + named.name;
  throw Error("unknown view '" + view + "': expected one of " + names);
}

void validateCamera(const Camera &c) {
  if (!(c.fovy > 0.f && c.fovy < 180.f))
    throw Error("fovy (the vertical view angle) must be between 0 and 180 degrees, exclusive; got " +
                std::to_string(c.fovy));
  if (!finite(c.eye))
    throw Error("the camera's eye must be finite; got " + text(c.eye));
  if (!finite(c.at))
    throw Error("the camera's focal point (at) must be finite; got " + text(c.at));
  if (!finite(c.up))
    throw Error("the camera's view-up (up) must be finite; got " + text(c.up));
  const Vec3f direction = c.at - c.eye;
  if (!finite(direction))
    throw Error("the camera's eye " + text(c.eye) + " and focal point (at) " + text(c.at) +
                " are too far apart for float arithmetic");
  if (!(length(direction) > 0.f))
    throw Error("the camera's eye and focal point (at) must differ; both are " + text(c.eye));
  if (!(length(c.up) > 0.f))
    throw Error("the camera's view-up (up) must not be zero");
  // Parallel within float precision: the image's horizontal axis would be undefined or noise.
  // Scaled to their largest component first: the length of a vector of components near 1e38 overflows.
  auto unit = [](Vec3f v) {
    const float largest = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    return normalize(v * (1.f / largest));
  };
  if (!(length(cross(unit(direction), unit(c.up))) > 1e-6f))
    throw Error("the camera's view-up (up) " + text(c.up) + " must not be parallel to the view direction " +
                text(direction) + " (from eye to at)");
}

} // namespace uvr
