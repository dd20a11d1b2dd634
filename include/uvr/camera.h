// A pinhole camera as ParaView describes one: eye, focal point, view-up and vertical view angle.
#pragma once

#include <uvr/vec.h>

#include <cmath>
#include <string>
#include <vector>

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

/// The named views, as ParaView's view-direction buttons have them: the side the camera looks from
/// (+x, -x, +y, -y, +z, -z) or `iso` (from +x+y+z). +z (looking down -z, +y up) is the reset camera.
std::vector<std::string> cameraViewNames();

/// ParaView's reset camera for `bounds` seen from the named view (cameraViewNames): view-up +z for the x and
/// y views, +y for the others. Throws uvr::Error listing the names for an unknown one, or for a bad fovy or
/// aspect (validateCamera's checks).
Camera frameBounds(const Box3f &bounds, const std::string &view, float fovy = 30.f, float aspect = 1.f);

/// Pixels [x0, x1) of rows [y0, y1) of an image, rows counted from the top.
struct PixelBox {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
};

/// The pixels of a `width` x `height` image of `camera` whose rays can meet `box`: the bounds of its corners'
/// projections and a pixel more on each side, or the whole image where a corner lies level with the eye or
/// behind it.
PixelBox boxPixels(const Camera &camera, int width, int height, const Box3f &box);

/// Throws uvr::Error for a camera no image can be made with: a vertical view angle not in (0, 180) degrees,
/// a non-finite eye, focal point or view-up, eye == focal point, a zero view-up or one parallel to the view
/// direction. The message names the field (fovy, eye, at, up). VolumeRenderer::render checks every camera.
void validateCamera(const Camera &camera);

} // namespace uvr
