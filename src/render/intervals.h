// The interval iterator (Open VKL's split: volume, sampler, interval iterator): a ray's intervals front to
// back, each with the step to sample it by. This is where the paper's space skipping (§2.2-2.3) and adaptive
// sampling (§2.4) live: skipping drops the partitions the transfer function makes transparent and the parts
// of the ray outside the mesh (before its first boundary crossing, after its last, and the gaps between a
// crossing out and the next one back in); adaptive sampling gives each partition a step from its colour
// deviation. Samples lie on one grid per ray (SampleGrid), so every sample is one that `reference` takes.
#pragma once

#include "accel/partitions.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "render/boundary_crossings.h"
#include "render/scene_view.h"
#include "render/transfer_function.h"

#include <uvr/settings.h>

#include <cmath>
#include <cstdint>

namespace uvr {

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
  float unit = 1.f;                               ///< opacity unit distance
  float terminationOpacity = kTerminationOpacity; ///< early ray termination
  bool preintegrate = false; ///< composite segments pre-integrated: the backends pick integrateRay<.., true>
  /// Scale each partition's steps by its cells' size (PartitionsView::stepScale), on a grid of the finest
  /// scale's spacing, rather than one s1 for the whole mesh.
  bool followMesh = false;
  /// Light the samples by the field's gradient as ShadingSettings says: the backends pick
  /// integrateRay<.., .., true>. Here, not at the end: the GPU's kernels copy these settings to local memory,
  /// and in the padding the unshaded kernels' copy does not grow.
  bool shade = false;
  /// Draw the backend's isosurfaces (RenderBackend::setIsoSurfaces): the backends pick
  /// integrateRay<.., .., false, true>, which shades the samples where `shade`. In the padding too.
  bool iso = false;
  /// Derived from s1, s2 and p by Renderer::render (finestStepSigma): partitions of greater sigma take step
  /// s1 outright, and subtrees of such partitions are marched whole. The default, +inf, computes every
  /// partition's step and, when sampling adaptively, marches every partition alone.
  float finestStepSigma = INFINITY;
  /// One piece of a mesh split among processes: where `clip` is not empty, the ray's sample grid starts where
  /// it enters `gridBounds` (the whole mesh's root bounds) and only its part inside `clip` (the piece's
  /// region) is marched, so that the pieces take the whole mesh's samples, each once.
  Box3f gridBounds, clip;
  /// A piece's: the whole mesh's finest step scale, which sets the grid's spacing where steps follow the
  /// mesh; 0 for the partitions' own.
  float finestStepScale = 0.f;
};

/// The paper's step size for a partition of normalised deviation `sigma` (§2.4).
UVR_HOST_DEVICE inline float adaptiveStepSize(float s1, float s2, float p, float sigma) {
  return maxf(s1 + (s2 - s1) * powf(fabsf(minf(sigma, 1.f) - 1.f), p), s1);
}

/// The sigma above which adaptiveStepSize rounds to one fixed step (the march's steps are whole numbers of
/// s1): where (s2 - s1) (1 - sigma)^p < s1 / 2. -inf where s2 = s1.
inline float finestStepSigma(float s1, float s2, float p) {
  return s2 > s1 ? 1.f - powf(0.5f * s1 / (s2 - s1), 1.f / p) : -INFINITY;
}

/// Where steps follow the mesh, a partition where the transfer function reaches this opacity (per unit
/// distance) takes half its step: there a step's samples decide where a ray stops, and few rays go on past
/// it, so the finer steps cost little beside what they fix. Translucent functions never reach it.
constexpr float kRefinedStepOpacity = 0.5f;

/// The finest step scale: the partitions', or a piece's whole mesh's.
UVR_HOST_DEVICE inline float finestStepScale(const IntegratorSettings &settings,
                                             const PartitionsView &partitions) {
  return settings.finestStepScale > 0.f ? settings.finestStepScale : partitions.finestStepScale;
}

/// The spacing of a ray's sample grid: s1, or where steps follow the mesh, half of s1 at the finest step
/// scale (the refined steps of opaque partitions).
UVR_HOST_DEVICE inline float gridSpacing(const IntegratorSettings &settings,
                                         const PartitionsView &partitions) {
  return settings.followMesh ? 0.5f * settings.s1 * finestStepScale(settings, partitions) : settings.s1;
}

/// The points a ray's samples lie on, t = origin + k * spacing, from where the ray enters the mesh bounds,
/// whatever the intervals: an interval's step is a whole number of spacings and its samples start at its
/// first grid point, so skipping alone changes no sample that contributes, and a step of one spacing
/// reproduces the fixed-step samples exactly. k is a float, exact to 2^24 grid points: Renderer::render
/// refuses steps that would take more (kMostSamplesPerRay, times the finest step scale).
struct SampleGrid {
  float origin = 0.f;
  float spacing = 1.f;

  UVR_HOST_DEVICE float at(float k) const { return origin + k * spacing; }
  /// The index of the first grid point at or after t.
  UVR_HOST_DEVICE float indexAt(float t) const {
    float k = ceilf((t - origin) / spacing);
    while (at(k) < t) // the division can round down
      k += 1.f;
    return k;
  }
};

/// The span [t0, t1] of `ray` inside `region`, one of the regions that the pieces of a mesh split space
/// into: a ray lying in a face that two regions share belongs to the region above the face alone, where the
/// slab test would give it to both.
UVR_HOST_DEVICE inline bool clipToRegion(const Ray &ray, const Box3f &region, float &t0, float &t1) {
  bool inside = intersectBox(ray, region, 0.f, INFINITY, t0, t1);
  for (int axis = 0; axis < 3; ++axis)
    if (ray.direction[axis] == 0.f)
      inside = inside && region.lower[axis] <= ray.origin[axis] && ray.origin[axis] < region.upper[axis];
  return inside;
}

/// One ray's intervals. forEach yields them with their steps, front to back; the march asks pastGap at each
/// grid point it samples, since the gaps between boundary crossings cut across the partitions.
class RayIntervals {
public:
  /// The intervals of `ray`: the partitions it crosses, each at its step, and with skipping only those drawn
  /// and only between the ray's first and last `crossings` with the mesh's boundary, where these are known;
  /// `reference`'s one interval spans the mesh bounds.
  UVR_HOST_DEVICE RayIntervals(const SceneView &scene, const IntegratorSettings &settings, const Ray &ray,
                               const BoundaryCrossings &crossings)
      : scene_(scene), settings_(settings), ray_(ray), crossings_(crossings) {
    // No early return: the fields then take one value on every path, which leaves the GPU's kernel fewer
    // values to keep (it spilled more with returns here).
    float tEnter, tExit;
    bool hit = intersectBox(ray, scene.partitions.rootBounds, 0.f, ray.tMax, tEnter, tExit);
    float gridOrigin = tEnter;
    if (!settings.clip.empty()) {
      float gridExit, clipEnter, clipExit;
      const bool inGrid = intersectBox(ray, settings.gridBounds, 0.f, INFINITY, gridOrigin, gridExit);
      const bool inClip = clipToRegion(ray, settings.clip, clipEnter, clipExit);
      hit = hit && inGrid && inClip;
      tEnter = maxf(maxf(tEnter, gridOrigin), clipEnter);
      tExit = minf(tExit, clipExit);
      hit = hit && tEnter < tExit;
    }
    grid_ = {gridOrigin, gridSpacing(settings, scene.partitions)};
    skip_ = skipsSpace(settings.mode);
    adaptive_ = samplesAdaptively(settings.mode);
    // A hundredth of a step of slack at crossings: rounding never leaves out a sample that `reference` finds
    // in a cell.
    margin_ = 0.01f * grid_.spacing;
    tStart_ = tEnter;
    tStop_ = tExit;
    gaps_ = false;
    none_ = !hit;
    if (skip_) {
      none_ = none_ || crossings.none();
      tStart_ = maxf(tEnter, crossings.first - margin_);
      tStop_ = minf(tExit, crossings.last + margin_);
      gaps_ = crossings.count > 1;
    }
  }

  /// Whether the ray meets no cell: it misses the mesh bounds or, skipping, every boundary face.
  UVR_HOST_DEVICE bool none() const { return none_; }
  UVR_HOST_DEVICE const SampleGrid &grid() const { return grid_; }
  /// The cell the ray enters the mesh by, where the skipping modes know it; else kNoCell.
  UVR_HOST_DEVICE uint32_t entryCell() const {
    return skip_ && crossings_.face != kNoCell ? boundaryFaceCell(scene_.mesh, crossings_.face) : kNoCell;
  }
  /// Whether every crossing is listed: samples then lie between them, in cells but for the margins.
  UVR_HOST_DEVICE bool crossingsListed() const { return crossings_.keys != nullptr; }

  /// Calls `visit(t0, t1, step)` for each partition's interval [t0, t1) front to back, until it returns
  /// false; `reference` marches the mesh bounds as one interval at step s1 (the root, marched whole). Then,
  /// where `end(t0, t1)` gives one, for a last interval past them at one grid spacing, from the same call.
  /// One traversal for every mode and one call of `visit`: the GPU's kernels then inline the march once for
  /// all of them.
  template <class Visit, class End> UVR_HOST_DEVICE void forEach(Visit &&visit, End &&end) const {
    // Skipping, the traversal culls transparent partitions and clips each interval to its shrunk box.
    traversePartitions(
        scene_.partitions, ray_, tStart_, tStop_, skip_ ? scene_.nodeMaxOpacity : nullptr,
        [&](uint32_t node) { return marchedWhole(node); },
        [&](uint32_t node, float t0, float t1) { return visit(t0, t1, step(node)); }, end);
  }

  /// The step through KD node `node`, a leaf or a subtree marched whole: the partition's adaptive step (paper
  /// §2.4), or s1 where that rounds to it or nothing is sampled adaptively; one grid spacing past the
  /// partitions (KdNode::kNone).
  UVR_HOST_DEVICE float step(uint32_t node) const {
    if (settings_.mode == RenderMode::Reference || node == KdNode::kNone)
      return grid_.spacing;
    // A whole node's partitions all take the finest step: s1 at the finest scale.
    const KdNode &n = scene_.partitions.nodes[node];
    if (n.axis != KdNode::kLeaf)
      return settings_.followMesh ? 2.f * grid_.spacing : grid_.spacing;
    const float scale = !settings_.followMesh ? 1.f
                        : scene_.nodeMaxOpacity[node] >= kRefinedStepOpacity
                            ? 0.5f * scene_.partitions.stepScale[n.child]
                            : scene_.partitions.stepScale[n.child];
    const float sigma = scene_.sigma[n.child];
    return scale * (takesFinestStep(sigma)
                        ? settings_.s1
                        : adaptiveStepSize(settings_.s1, settings_.s2, settings_.p, sigma));
  }

  /// Whether t lies past the ray's last boundary crossing, where the skipping modes know it: only a boundary
  /// cell bulging past the triangles the crossings were found on can hold a point there. (Not the end of
  /// the march, which a piece's region or the ray's limit may set inside the mesh.)
  UVR_HOST_DEVICE bool pastMesh(float t) const { return skip_ && t > crossings_.last + margin_; }
  /// Whether the ray leaves the mesh and enters it again: grid points may then lie in a gap (pastGap).
  UVR_HOST_DEVICE bool hasGaps() const { return gaps_; }
  /// Where the march goes on from grid point t: past the gap in the mesh that holds t, if one does, else t;
  /// `entered` the face the ray comes back in by (see afterGap). t only grows along a ray.
  UVR_HOST_DEVICE float pastGap(float t, uint32_t &entered) {
    return afterGap(crossings_, t, margin_, cursor_, entered);
  }
  /// Where the ray last left the mesh and came back in, as pastGap last met them.
  UVR_HOST_DEVICE float gapExit() const { return cursor_.gapExit; }
  UVR_HOST_DEVICE float gapEntry() const { return cursor_.gapEntry; }
  /// Where the ray last left the mesh at or before t, where the skipping modes know it; else -inf.
  UVR_HOST_DEVICE float exitBefore(float t) const {
    if (!skip_)
      return -INFINITY;
    float exit = crossings_.keys ? cursor_.gapExit : crossings_.last;
    for (uint32_t i = cursor_.next; i < crossings_.count && crossingT(crossings_.keys[i]) <= t; ++i)
      if (crossingExits(crossings_.keys[i]))
        exit = crossingT(crossings_.keys[i]);
    return exit <= t ? exit : -INFINITY;
  }

private:
  /// Whether partitions of deviation `sigma` take step s1.
  UVR_HOST_DEVICE bool takesFinestStep(float sigma) const {
    return !adaptive_ || sigma > settings_.finestStepSigma;
  }
  /// Whether the subtree under `node` is one interval: its partitions all drawn and all taking step s1, so
  /// that marching it leaf by leaf would take the same samples at a higher cost (on a GPU, a large part of a
  /// `full` frame); in `reference`, every node.
  UVR_HOST_DEVICE bool marchedWhole(uint32_t node) const {
    if (settings_.mode == RenderMode::Reference)
      return true;
    const float sigma = scene_.nodeMinSigma[node];
    return sigma != kTransparentSigma && takesFinestStep(sigma) &&
           (!settings_.followMesh ||
            (scene_.partitions.nodeMaxStepScale[node] <= finestStepScale(settings_, scene_.partitions) &&
             scene_.nodeMaxOpacity[node] < kRefinedStepOpacity));
  }

  const SceneView &scene_;
  const IntegratorSettings &settings_;
  const Ray &ray_;
  const BoundaryCrossings &crossings_;
  bool none_;
  SampleGrid grid_;
  float tStart_, tStop_; ///< the span the skipping modes march, crossings and margins included
  float margin_;
  bool skip_, adaptive_, gaps_;
  CrossingCursor cursor_; ///< the march's place among the crossings
};

} // namespace uvr
