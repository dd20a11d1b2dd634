// The ray integrator shared by every backend: emission-absorption ray marching with the paper's space
// skipping (§2.3) and adaptive sampling (§2.4). Plain data in, no virtual calls, no exceptions.
#pragma once

#include "accel/partitions.h"
#include "accel/sampler.h"
#include "core/host_device.h"
#include "mesh/cell.h"
#include "render/boundary_crossings.h"
#include "render/scene_view.h"
#include "render/transfer_function.h"

#include <cstdint>

namespace uvr {

enum class RenderMode : uint8_t {
  Reference, ///< fixed step s1 over the mesh bounds, nothing skipped
  Skip,      ///< fixed step s1, transparent partitions and empty space skipped
  Adaptive,  ///< step per partition from its colour variance, nothing skipped
  Full       ///< both
};

/// Whether `mode` skips transparent partitions and empty space.
UVR_HOST_DEVICE constexpr bool skipsSpace(RenderMode mode) {
  return mode == RenderMode::Skip || mode == RenderMode::Full;
}

/// Whether `mode` steps through each partition by its colour variance.
UVR_HOST_DEVICE constexpr bool samplesAdaptively(RenderMode mode) {
  return mode == RenderMode::Adaptive || mode == RenderMode::Full;
}

struct IntegratorSettings {
  RenderMode mode = RenderMode::Full;
  float s1 = 1.f, s2 = 1.f, p = 2.f;
  float unit = 1.f;                 ///< opacity unit distance
  float terminationOpacity = 0.99f; ///< early ray termination
  /// Derived from s1, s2 and p by Renderer::render (finestStepSigma): partitions of greater sigma take step
  /// s1 outright, and subtrees of such partitions are marched whole. The default, +inf, computes every
  /// partition's step and, when sampling adaptively, marches every partition alone.
  float finestStepSigma = INFINITY;
};

struct RayResult {
  Vec4f color; ///< premultiplied rgb, accumulated opacity
  uint32_t samples = 0;
};

/// Integrates one ray front to back. Samples lie on the grid t = tEnter + k * s1 fixed along the ray (tEnter:
/// where it enters the mesh bounds); a partition's adaptive step is rounded to a whole number of s1 and its
/// march starts at its first grid point, so every sample is one that `reference` takes: skipping alone
/// changes no sample that contributes, and a step of s1 reproduces the fixed-step samples exactly. `hint` is
/// a cell near the ray's first sample (the neighbouring pixel's: rays are coherent), or kNoCell; it is
/// updated to this ray's first cell. `trail` holds, by grid index k, the previous ray's guesses at this ray's
/// tets, and takes this ray's at the next one's, where the sampling policy follows one. The skipping modes
/// march only between the ray's first and last boundary crossings, and not through the gaps between them that
/// lie outside the mesh, where `crossings` knows them.
template <class Sampling>
UVR_HOST_DEVICE inline RayResult integrateRay(const SceneView &scene, const IntegratorSettings &settings,
                                              const Ray &ray, uint32_t &hint,
                                              const BoundaryCrossings &crossings, CellTrail trail = {}) {
  RayResult result;
  float tEnter, tExit;
  if (!intersectBox(ray, scene.partitions.rootBounds, 0.f, INFINITY, tEnter, tExit))
    return result;

  const bool skip = skipsSpace(settings.mode), adaptive = samplesAdaptively(settings.mode);
  // Rejecting samples in empty space is part of space skipping: the modes without it locate every sample the
  // plain way, as the paper's reference ray marcher does.
  // Where the crossings are known, samples lie between them, in cells but for the margins: the occupancy
  // grid would only confirm it.
  RaySampler<Sampling> sampler(scene, ray, hint, skip, crossings.keys == nullptr);
  bool first = true;
  float tStart = tEnter, tStop = tExit;
  // A hundredth of a step of slack at crossings: rounding never leaves out a sample that `reference` finds in
  // a cell.
  const float margin = 0.01f * settings.s1;
  if (skip) {
    if (crossings.none())
      return result;
    tStart = maxf(tEnter, crossings.first - margin);
    tStop = minf(tExit, crossings.last + margin);
    if (crossings.face != kNoCell)
      sampler.enter(crossings.face >> 2);
  }
  const float s1 = settings.s1;
  // The next ray's grid starts where it enters the mesh bounds, as this one's does.
  sampler.follow(trail, scene.partitions.rootBounds, s1);
  // Grid points in the gaps between the ray's crossings out of the mesh and back in are passed over; the
  // march goes on from the tet the ray re-enters by. `crossing` follows the march along the crossings.
  const bool gaps = skip && crossings.count > 1;
  CrossingCursor crossing;
  // The index of the first grid point at or after t.
  auto gridIndex = [&](float t) {
    float k = ceilf((t - tEnter) / s1);
    while (tEnter + k * s1 < t) // the division can round down
      k += 1.f;
    return k;
  };
  // Marches [ta, tb) with step `step`; false once the ray is opaque.
  auto march = [&](float ta, float tb, float step) {
    float k = gridIndex(ta);
    // A sample stands for the distance to the next one; the last one before tb for the distance to the grid
    // point where the next interval's samples begin, so that intervals marched with longer steps neither
    // overlap nor leave gaps at partition boundaries (with step s1 nothing changes).
    const float kEnd = gridIndex(tb);
    // Whole fixed steps: every sample is one of reference's, and at the default unit the opacity needs no
    // correction for most of them.
    const float stride = maxf(1.f, rintf(step / s1));
    // A longer step crosses proportionally more tets; past a seed voxel, the seed lies nearer than the
    // previous sample.
    const int walkSteps = 8 * int(stride);
    const bool far = stride * s1 > scene.seeds.grid.voxelEdge();
    // In registers, not in `result`: with the sampler inlined on the host, the loop makes no call, and each
    // sample's colour does not wait on the store of the last one's.
    Vec4f color = result.color;
    uint32_t samples = result.samples;
    bool opaque = false;
    for (float t = tEnter + k * s1; t < tb; k += stride, t = tEnter + k * s1) {
      if (gaps) {
        uint32_t entered;
        const float resume = afterGap(crossings, t, margin, crossing, entered);
        if (entered != kNoCell)
          sampler.enter(entered >> 2);
        if (resume > t) {
          k = gridIndex(resume);
          t = tEnter + k * s1;
          if (!(t < tb))
            break;
        }
      }
      ++samples;
      float value;
      if (!sampler.sample(t, k, walkSteps, far, value))
        continue;
      if (first) {
        hint = sampler.cell();
        first = false;
      }
      const Vec4f c = scene.tf.sample(value);
      if (c.w <= 0.f)
        continue;
      // Opacity per unit distance, corrected to the distance this sample stands for (paper §2.4, DESIGN §5).
      const bool last = !(tEnter + (k + stride) * s1 < tb);
      const float exponent = (last ? kEnd - k : stride) * s1 / settings.unit;
      // At the default unit, s1, fixed steps need no correction: powf was 7 % of a CPU frame.
      const float alpha = exponent == 1.f ? minf(c.w, 1.f) : 1.f - powf(maxf(1.f - c.w, 0.f), exponent);
      const float weight = (1.f - color.w) * alpha;
      color.x += weight * c.x;
      color.y += weight * c.y;
      color.z += weight * c.z;
      color.w += weight;
      if (color.w >= settings.terminationOpacity) {
        opaque = true;
        break;
      }
    }
    result.color = color;
    result.samples = samples;
    return !opaque;
  };

  if (settings.mode == RenderMode::Reference) {
    march(tEnter, tExit, settings.s1);
    return result;
  }
  // With skipping, the traversal culls transparent partitions and clips each interval to its shrunk box. A
  // subtree whose partitions are all drawn and all take step s1 is marched in one go: leaf by leaf, its
  // march would take the same samples. On a GPU, descending leaf by leaf was a third of a `full` frame's
  // render kernel (H100, 12.1M tets: 1.31 ms against 0.87 marching each ray in one go).
  const float *cull = skip ? scene.nodeMaxOpacity : nullptr;
  auto fine = [&](float sigma) { return !adaptive || sigma > settings.finestStepSigma; };
  auto whole = [&](uint32_t node) {
    const float sigma = scene.nodeMinSigma[node];
    return sigma != kTransparentSigma && fine(sigma);
  };
  traversePartitions(
      scene.partitions, ray, tStart, tStop, cull, whole, [&](uint32_t node, float t0, float t1) {
        // A whole node's partitions all take step s1.
        const KdNode &n = scene.partitions.nodes[node];
        const bool fixed = n.axis != KdNode::kLeaf || fine(scene.sigma[n.child]);
        return march(t0, t1,
                     fixed ? s1 : adaptiveStepSize(s1, settings.s2, settings.p, scene.sigma[n.child]));
      });
  return result;
}

} // namespace uvr
