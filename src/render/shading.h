// Gradient shading of the samples: the field's gradient per point (computed on the host, see
// mesh/point_gradients.h), interpolated to each sample, lights the transfer function's colour with a
// Blinn-Phong model. Plain data, on host and device alike.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"

#include <cmath>

namespace uvr {

/// The change of the field across a mean cell (the mesh bounds' diagonal over the cube root of the cell
/// count), as a fraction of the transfer function's range, at and above which a sample is fully lit.
constexpr float kFullyLitChange = 0.125f;

/// How a frame is lit: a parameter of the shaded kernels alone, so that the unshaded ones are as they were.
struct ShadingSettings {
  const Vec3f *gradients = nullptr; ///< per point, the field's gradient (on the device for CUDA)
  bool headlight = true;            ///< the light sits at the eye; else it shines from `light`
  /// Towards the light, where not `headlight`: in camera space (x right, y up, z towards the eye) as
  /// Renderer::render takes it, in world space and of unit length as the march reads it.
  Vec3f light{0.f, 0.f, 1.f};
  float ambient = 0.2f, diffuse = 0.7f, specular = 0.2f, shininess = 16.f;
  /// 1 / the gradient magnitude at and above which a sample is fully lit: below it the lit colour fades into
  /// the unlit one, so that the noise of near-uniform regions, whose gradients point anywhere, is not lit.
  float fullGradientInverse = 0.f;
};

/// The colour `rgb` lit where the surface's unit normal is `normal`, seen along `toEye` (unit, from the point
/// towards the eye): Blinn-Phong with a white light, two-sided (the gradient's sign says nothing of which
/// side a surface faces the eye).
UVR_HOST_DEVICE inline Vec3f blinnPhong(Vec3f rgb, Vec3f normal, Vec3f toEye, const ShadingSettings &s) {
  const Vec3f light = s.headlight ? toEye : s.light;
  const Vec3f half = s.headlight ? toEye : normalize(light + toEye);
  const float diffuse = fabsf(dot(normal, light));
  const float highlight = s.specular * powf(fabsf(dot(normal, half)), s.shininess);
  const float scale = s.ambient + s.diffuse * diffuse;
  return {rgb.x * scale + highlight, rgb.y * scale + highlight, rgb.z * scale + highlight};
}

/// The colour `rgb` of a sample where the field's gradient is `gradient`, seen along `toEye`: blinnPhong,
/// blended with `rgb` by the gradient's magnitude.
UVR_HOST_DEVICE inline Vec3f shadeColor(Vec3f rgb, Vec3f gradient, Vec3f toEye, const ShadingSettings &s) {
  const float magnitude = length(gradient);
  const float lit = minf(1.f, magnitude * s.fullGradientInverse);
  if (!(lit > 0.f)) // also a NaN gradient
    return rgb;
  return rgb + (blinnPhong(rgb, gradient * (1.f / magnitude), toEye, s) - rgb) * lit;
}

/// The colour `rgb` of an isosurface where the field's gradient, its normal, is `gradient`: lit whatever
/// the gradient's magnitude (a surface is no noise), as if facing the eye where the gradient is 0.
UVR_HOST_DEVICE inline Vec3f shadeSurface(Vec3f rgb, Vec3f gradient, Vec3f toEye, const ShadingSettings &s) {
  const float magnitude = length(gradient);
  return blinnPhong(rgb, magnitude > 0.f ? gradient * (1.f / magnitude) : toEye, toEye, s);
}

} // namespace uvr
