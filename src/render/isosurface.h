// Implicit isosurfaces: the surfaces where the field takes given values, found along each ray where the
// field crosses a value between two of its samples and composited with the volume at their depth (see
// RayMarch). Plain data, on host and device alike.
#pragma once

#include "core/host_device.h"
#include "core/vec.h"

#include <uvr/settings.h>

#include <cstdint>

namespace uvr {

/// The most isosurfaces a frame draws: their values travel by value in the GPU's kernel parameters.
constexpr uint32_t kMaxIsoValues = kMaxIsoSurfaces;

/// Bisection or secant steps that refine a crossing in cells other than tets (and bound the walk to it in
/// tets, where the field is linear along the ray and the root is closed-form once its tet is found).
constexpr int kIsoRefineSteps = 10;

/// The isosurfaces of a frame: a parameter of the isosurface kernels alone.
struct IsoSettings {
  uint32_t count = 0;
  float values[kMaxIsoValues] = {};
  Vec3f colors[kMaxIsoValues] = {}; ///< per value, unlit
  float opacity = 1.f;              ///< of each surface
  bool hideVolume = false;          ///< draw the surfaces alone: the volume is transparent

  /// Whether a value in [lo, hi] lies on a surface: a partition of that range must be marched.
  UVR_HOST_DEVICE bool crossesRange(float lo, float hi) const {
    for (uint32_t i = 0; i < count; ++i)
      if (lo <= values[i] && values[i] <= hi)
        return true;
    return false;
  }
  /// The settings that decide which partitions are marched (the partitions' metadata depends on them).
  bool sameSkipping(const IsoSettings &other) const {
    if (count != other.count || hideVolume != other.hideVolume)
      return false;
    for (uint32_t i = 0; i < count; ++i)
      if (values[i] != other.values[i])
        return false;
    return true;
  }
};

/// The maximum opacity that marks a partition which is transparent but holds an isosurface: above 0, so
/// that the traversal visits it, and far below anything that changes its steps.
constexpr float kIsoVisitOpacity = 1e-20f;

/// Whether the field crosses `value` between samples `a` and `b` (one may equal it, not both).
UVR_HOST_DEVICE inline bool crossesValue(float a, float b, float value) { return (a < value) != (b < value); }

} // namespace uvr
