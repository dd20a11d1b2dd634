// The ray integrator shared by every backend: emission-absorption ray marching (Open VKL's split: the
// interval iterator, intervals.h, yields the ray's intervals and their steps, with the paper's space skipping
// (§2.3) and adaptive sampling (§2.4); the sampler, accel/sampler.h, locates and interpolates each sample;
// the march here composites them). Plain data in, no virtual calls, no exceptions.
#pragma once

#include "accel/sampler.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "render/boundary_crossings.h"
#include "render/intervals.h"
#include "render/isosurface.h"
#include "render/scene_view.h"
#include "render/shading.h"

#include <cmath>
#include <cstdint>

namespace uvr {

struct RayResult {
  Vec4f color; ///< premultiplied rgb, accumulated opacity
  uint32_t samples = 0;
};

/// Adds a segment of colour `c` (rgb, opacity) behind what `color` (premultiplied rgb, opacity) holds. Where
/// that makes the ray `terminationOpacity` opaque, the ray ends there, and the light it would still let
/// through is given `c`'s colour: the rest of the ray taken to look like its last segment, not dropped, so
/// that where a ray ends depends little on where it began (the ranks of a split mesh begin theirs at their
/// regions' faces).
UVR_HOST_DEVICE inline void compositeBehind(Vec4f &color, const Vec4f &c, float terminationOpacity) {
  float weight = (1.f - color.w) * c.w;
  if (color.w + weight >= terminationOpacity)
    weight = 1.f - color.w;
  color.x += weight * c.x;
  color.y += weight * c.y;
  color.z += weight * c.z;
  color.w += weight;
}

/// The march of one ray through its intervals: samples each on the ray's grid, looks the samples up in the
/// transfer function and composites them front to back, until the ray is opaque. Point compositing (the
/// paper's) gives each sample's colour to the distance to the next sample; pre-integration (kPreintegrate)
/// gives each segment between two samples the function integrated over the values between them. A template
/// parameter, not a setting: the GPU's kernel for point samples then carries none of pre-integration's state.
/// Shading (kShade) likewise: it lights each sample's colour, or each segment's by the gradient at its start,
/// and the unshaded kernels hold none of it. Isosurfaces (kIso) too: where the field crosses a surface's
/// value between two points sampled, the crossing is refined (isoCrossing) and the surface, lit by the
/// gradient there, is composited behind the segment that holds it; these kernels shade the volume as
/// IntegratorSettings::shade says, so that isosurfaces double no other kernel.
template <bool kShade> struct ShadeState {}; ///< unshaded, nothing: the GPU's kernels keep their size

/// What a shaded march carries besides the unshaded one's.
template <> struct ShadeState<true> {
  const ShadingSettings *shading;
  Vec3f pendingGradient; ///< the gradient at the pending sample
  Vec3f toEye;           ///< along the ray towards the eye
};

template <bool kIso> struct IsoState {}; ///< no surfaces, nothing

/// What a march that draws isosurfaces carries: the last point where the field is known. Of its cell, the
/// index and the field's slope along the ray, not the whole record (RayCell): the GPU's kernels then keep
/// no second one, and a crossing there is still found without a probe.
template <> struct IsoState<true> {
  const IsoSettings *iso;
  float lastT = 0.f, lastValue = 0.f;
  uint32_t lastCell = kNoCell;   ///< the cell of the last point
  float lastSlope = NAN;         ///< the field's change per unit t there, where the cell is a tet
  bool lastValid = false;        ///< whether a cell held the last point, and the field is continuous since
  float intervalEnd = -INFINITY; ///< where the last interval marched ends
};

template <class Sampling, bool kPreintegrate, bool kShade = false, bool kIso = false>
struct RayMarch : ShadeState<kShade || kIso>, IsoState<kIso> {
  static constexpr bool kLit = kShade || kIso; ///< whether the march holds shading's state
  const SceneView &scene;
  const IntegratorSettings &settings;
  RayIntervals &intervals;
  RaySampler<Sampling> &sampler;
  uint32_t &hint; ///< set to the ray's first cell
  RayResult result = {};
  bool first = true;
  /// Pre-integrating, the last sample: its segment reaches to grid point `next`, and is integrated to the
  /// value there (the next sample's or, where the march would not sample there, one taken to close it). For
  /// cell data, `exit`: how far past the sample the ray leaves its cell (NaN where unknown), where the
  /// segment's value steps to the next one; `cell`: that cell.
  struct Pending {
    float value = 0.f, k = 0.f, next = 0.f, exit = 0.f;
    bool valid = false;
    uint32_t cell = kNoCell;
  } pending;

  UVR_HOST_DEVICE RayMarch(const SceneView &scene, const IntegratorSettings &settings,
                           RayIntervals &intervals, RaySampler<Sampling> &sampler, uint32_t &hint,
                           const ShadingSettings *shading = nullptr, const IsoSettings *iso = nullptr)
      : scene(scene), settings(settings), intervals(intervals), sampler(sampler), hint(hint) {
    if constexpr (kLit) {
      this->shading = shading;
      this->toEye = normalize(Vec3f{} - sampler.ray.direction);
    }
    if constexpr (kIso)
      this->iso = iso;
  }

  /// Whether the volume's samples are lit.
  UVR_HOST_DEVICE bool shadesVolume() const { return kShade || settings.shade; }
  /// Whether the volume is drawn at all.
  UVR_HOST_DEVICE bool drawsVolume() const {
    if constexpr (kIso)
      return !this->iso->hideVolume;
    return true;
  }

  /// Samples [ta, tb) every `step`, rounded to whole grid spacings; false once the ray is opaque.
  UVR_HOST_DEVICE bool interval(float ta, float tb, float step) {
    const SampleGrid &grid = intervals.grid();
    const float spacing = grid.spacing;
    float k = grid.indexAt(ta);
    // A sample stands for the distance to the next one; the last one before tb for the distance to the grid
    // point where the next interval's samples begin, so that intervals marched with longer steps neither
    // overlap nor leave gaps at partition boundaries (with a step of one spacing nothing changes).
    const float kEnd = grid.indexAt(tb);
    // Whole fixed steps: every sample is one of reference's, and at the default unit the opacity needs no
    // correction for most of them.
    const float stride = maxf(1.f, rintf(step / spacing));
    // A longer step crosses proportionally more tets; past a seed voxel, the seed lies nearer than the
    // previous sample.
    const int walkSteps = 8 * int(stride);
    const bool far = stride * spacing > scene.seeds.grid.voxelEdge();
    // Pre-integrating, where space was skipped since the pending sample, the first sample closes its segment
    // (a thin feature of the function near the end of the last interval is found only by integrating to
    // that end) before the march goes on from k.
    bool closing = kPreintegrate && pending.valid && k != pending.next;
    const float kStart = k;
    if (closing)
      k = pending.next;
    // In registers, not in `result`: with the sampler inlined on the host, the loop makes no call, and each
    // sample's colour does not wait on the store of the last one's.
    Vec4f color = result.color;
    uint32_t samples = result.samples;
    bool opaque = false;
    // Where a sample is the interval's first or follows one in the mesh and lies outside, a longer step goes
    // on one spacing at a time up to where its next sample lies (kAligned): where the ray comes back into
    // the mesh within the step (a hole, a concave boundary, a box reaching past its cells), the part inside
    // is not lost with the sample that missed. Further on in a gap the step is kept: a long gap costs no
    // more samples.
    float kAligned = k, kNext = k;
    bool lastInside = true;
    if constexpr (kIso) {
      // Where this interval does not go on from the last one, what lies between is skipped (its range holds
      // no surface) or outside the mesh: the field there is unknown, and a surface ahead of the first sample
      // is found from a point just inside the interval: past the intervals' margin, which may reach a little
      // out of the mesh.
      if (!(fabsf(ta - this->intervalEnd) <= 0.01f * spacing)) {
        this->lastValid = false;
        const float tProbe = ta + 0.02f * spacing;
        float value;
        if (tProbe < grid.at(kStart)) {
          ++samples;
          const bool inside = sampler.probe(tProbe, walkSteps, far, value);
          isoAt(color, samples, tProbe, value, inside, walkSteps);
        }
      }
    }
    for (float t = grid.at(k); closing || t < tb; k = kNext, t = grid.at(k)) {
      // Grid points in the gaps between the ray's crossings out of the mesh and back in are passed over; the
      // march goes on from the cell the ray re-enters by.
      if (!closing && intervals.hasGaps()) {
        uint32_t entered;
        const float resume = intervals.pastGap(t, entered);
        if constexpr (kIso) {
          if (entered != kNoCell && isoAcrossGap(color, samples, entered,
                                                 resume > t ? grid.at(grid.indexAt(resume)) : t, walkSteps)) {
            opaque = true;
            break;
          }
        }
        if (entered != kNoCell)
          sampler.enter(boundaryFaceCell(scene.mesh, entered));
        if (resume > t) {
          k = grid.indexAt(resume);
          t = grid.at(k);
          if (!(t < tb))
            break;
        }
      }
      ++samples;
      float value;
      // A segment closed past the ray's last crossing out of the mesh: its end lies outside but for the
      // boundary's bulges, which the walk finds; the slow ways a missed sample takes would find nothing more
      // (on a GPU, a BVH query that keeps the warp waiting).
      const bool inside = locate(t, k, walkSteps, far, value, closing && intervals.pastMesh(t));
      if constexpr (kIso) {
        // A sample past where the ray left the mesh, the last one inside: a surface between them is found
        // from just inside the exit.
        if (!inside && isoBeforeExit(color, samples, intervals.exitBefore(t), walkSteps)) {
          opaque = true;
          break;
        }
      }
      const bool refining = kAligned > k;
      kNext = refining ? (inside ? kAligned : k + 1.f) : k + stride;
      if constexpr (kPreintegrate) {
        // The pending segment ends here: at its end (closing, or the next sample joining it) it runs to the
        // value there, else (outside the mesh, or past a gap) it keeps its own. One call site: the GPU's
        // kernel inlines the integration once.
        if (pending.valid) {
          const bool joined = inside && (closing || k == pending.next);
          closeSegment(color, samples, joined ? value : pending.value, spacing);
        }
      }
      if constexpr (kIso) {
        isoAt(color, samples, t, value, inside, walkSteps);
        if (color.w >= settings.terminationOpacity) {
          opaque = true;
          break;
        }
      }
      if constexpr (kPreintegrate) {
        if (closing) {
          closing = false;
          if (color.w >= settings.terminationOpacity) {
            opaque = true;
            break;
          }
          kNext = kStart;
          continue;
        }
      }
      const bool entering = lastInside;
      lastInside = inside;
      if (!inside) {
        if (entering && !refining && stride > 1.f) {
          kAligned = k + stride;
          kNext = k + 1.f;
        }
        continue;
      }
      if (first) {
        hint = sampler.cell();
        first = false;
      }
      const bool last = !(grid.at(kNext) < tb);
      if constexpr (kPreintegrate) {
        // Recorded now: the sampler moves on.
        const float exit = scene.mesh.cellCentered ? sampler.at.crossingT(inHex(), true) - t : 0.f;
        const uint32_t cell = Sampling::kCellsBetweenSamples ? sampler.cell() : kNoCell; // for crossCells
        pending = {value, k, last ? kEnd : kNext, exit, true, cell};
        if constexpr (kLit) {
          if (shadesVolume())
            this->pendingGradient = sampler.pointVectorAt(this->shading->gradients, t);
        }
      } else {
        if (!drawsVolume())
          continue;
        Vec4f c = scene.tf.sample(value);
        if (c.w <= 0.f)
          continue;
        if constexpr (kLit) {
          if (shadesVolume())
            c = shade(c, sampler.pointVectorAt(this->shading->gradients, t));
        }
        compositeBehind(
            color,
            {c.x, c.y, c.z, correctedOpacity(c.w, ((last ? kEnd : kNext) - k) * spacing, settings.unit)},
            settings.terminationOpacity);
      }
      if (color.w >= settings.terminationOpacity) {
        opaque = true;
        break;
      }
    }
    if constexpr (kIso) {
      // A surface between the last sample and the interval's end: the next interval may not go on from here.
      // Just before the end (where the ray's limit may end it); where that lies outside the mesh (the
      // interval reaches a little past a boundary crossing), just inside the crossing, or where none is
      // known, past the intervals' margin.
      float tProbe = tb - 1e-4f * spacing;
      if (!opaque && this->lastValid && tProbe > this->lastT) {
        ++samples;
        float value;
        bool inside = sampler.probe(tProbe, walkSteps, false, value);
        if (!inside) {
          const float exit = intervals.exitBefore(tb);
          const float inner = exit > -INFINITY ? exit - 0.01f * spacing : tb - 0.02f * spacing;
          if (inner > this->lastT) {
            tProbe = inner;
            ++samples;
            inside = sampler.probe(tProbe, walkSteps, false, value);
          }
        }
        isoAt(color, samples, tProbe, value, inside, walkSteps);
        opaque = color.w >= settings.terminationOpacity;
      }
      this->intervalEnd = tb;
    }
    result.color = color;
    result.samples = samples;
    return !opaque;
  }

  /// After the ray's last interval, the one that closes a pending sample's segment where the ray is not yet
  /// opaque: an empty interval past the segment's end, whose one sample closes the segment. False where there
  /// is none.
  UVR_HOST_DEVICE bool closingInterval(float &t0, float &t1) const {
    if (!kPreintegrate || !pending.valid || !(result.color.w < settings.terminationOpacity))
      return false;
    t0 = t1 = intervals.grid().at(pending.next + 1.f);
    return true;
  }

private:
  /// The field at `t`, grid point `k`, as RaySampler::sample takes it. Where the policy says so, a march that
  /// draws isosurfaces locates its samples by the probe that its search calls at intervals' ends and in each
  /// crossing's refinement: one copy of the locate in the kernel, not one at each of those places.
  UVR_HOST_DEVICE UVR_HOST_INLINE bool locate(float t, float k, int walkSteps, bool far, float &value,
                                              bool pastMesh) {
    if constexpr (kIso && Sampling::kIsoSamplesByProbe)
      return sampler.probe(t, walkSteps, far, value, pastMesh);
    else
      return sampler.sample(t, k, walkSteps, far, value, pastMesh);
  }

  /// Composites the pending segment, its value running linearly to `endValue` at its end. Cell data steps
  /// instead, from the pending value to `endValue` halfway between where the ray leaves the pending sample's
  /// cell and where it enters the end's (cells between, which neither sample lies in, count half to each);
  /// where one crossing is unknown, at the other, where both are, at the segment's middle. Where the policy
  /// affords it, the cells between that could show are visited first (crossCells).
  UVR_HOST_DEVICE void closeSegment(Vec4f &color, uint32_t &samples, float endValue, float spacing) {
    pending.valid = false;
    if (!drawsVolume())
      return;
    const float length = (pending.next - pending.k) * spacing;
    Vec4f c;
    if (!scene.mesh.cellCentered) {
      c = scene.tf.integrate(pending.value, endValue, length, settings.unit);
    } else {
      // The last piece: `value` from `from` to where the ray leaves its cell, `exit`, then `endValue`.
      float from = 0.f, value = pending.value, split = length;
      // Where the values differ, the segment ends in another cell: the sampler's now.
      if (endValue != pending.value) {
        const float tStart = intervals.grid().at(pending.k);
        float exit = pending.exit;
        const float entry = sampler.at.crossingT(inHex(), false) - tStart;
        if constexpr (Sampling::kCellsBetweenSamples)
          crossCells(color, samples, endValue, tStart, entry, spacing, from, value, exit);
        split = 0.5f * ((exit == exit ? exit : entry) + (entry == entry ? entry : exit));
        split = split == split ? clampf(split, from, length) : 0.5f * (from + length);
      }
      c = scene.tf.step(value, endValue, split - from, length - split, settings.unit);
    }
    compositeSegment(color, c);
  }

  /// Composites a segment's colour behind `color`, lit by the pending sample's gradient where shading.
  UVR_HOST_DEVICE void compositeSegment(Vec4f &color, Vec4f c) {
    if constexpr (kLit) {
      if (shadesVolume())
        c = shade(c, this->pendingGradient);
    }
    compositeBehind(color, c, settings.terminationOpacity);
  }

  /// A cell field's segment from `tStart` whose two samples lie in cells apart, `exit` and `entry` past its
  /// start: where its value over that stretch, either sample's, could change its opacity by more than
  /// kCellStepTolerance (bounded by the extinctions' difference times the stretch: no exp), the cells
  /// between are found one by one just past the last one's exit, and each one's piece composited, up to the
  /// end's cell or one whose exit is unknown. `from`, `value` and `exit` then describe the last piece; the
  /// sampler is back at the segment's end.
  UVR_HOST_DEVICE void crossCells(Vec4f &color, uint32_t &samples, float endValue, float tStart, float entry,
                                  float spacing, float &from, float &value, float &exit) {
    constexpr float kCellStepTolerance = 0.1f;
    constexpr int kMostCells = 64;
    constexpr int kWalk = 8;             // steps of each walk: the next cell is a neighbour
    const float nudge = 1e-3f * spacing; // past a face, within float precision of t
    const float stretch = entry - exit;
    if (!(stretch > nudge) ||
        !(fabsf(scene.tf.extinctionAt(value) - scene.tf.extinctionAt(endValue)) * stretch >
          kCellStepTolerance * settings.unit))
      return;
    sampler.enter(pending.cell);
    for (int cells = 0; exit < entry - nudge && cells < kMostCells; ++cells) {
      float next;
      ++samples;
      if (!sampler.probe(tStart + exit + nudge, kWalk, false, next))
        break;
      const float nextExit = sampler.at.crossingT(inHex(), true) - tStart;
      if (!(nextExit > exit))
        break;
      compositeSegment(color, scene.tf.step(value, value, exit - from, 0.f, settings.unit));
      from = exit;
      value = next;
      exit = nextExit;
    }
    float atEnd;
    sampler.probe(intervals.grid().at(pending.next), kWalk, false, atEnd);
  }

  /// Whether the sampler's cell is a hexahedron.
  UVR_HOST_DEVICE bool inHex() const { return cellType(scene.mesh, sampler.cell()) == CellType::Hexahedron; }

  /// Takes the field at `t` (`value`; `inside`: whether a cell holds the point), a point past the last one
  /// known, and composites the surfaces it crosses on the way from there, nearest first: in the order of
  /// their values (sorted ascending by the host), upwards where the field rises. The sampler ends in `t`'s
  /// cell.
  UVR_HOST_DEVICE void isoAt(Vec4f &color, uint32_t &samples, float t, float value, bool inside,
                             int walkSteps) {
    if (!(t > this->lastT) && this->lastValid)
      return; // behind what is known already (a closing sample past a probe)
    const bool bracket = this->lastValid && inside;
    const float t0 = this->lastT, v0 = this->lastValue;
    const uint32_t cell0 = this->lastCell;
    const float slope0 = this->lastSlope;
    this->lastT = t;
    this->lastValue = value;
    this->lastValid = inside;
    this->lastCell = sampler.cell();
    this->lastSlope = sampler.at.affine ? sampler.at.dvalue : NAN;
    if (!bracket)
      return;
    const IsoSettings &iso = *this->iso;
    const bool rising = value > v0;
    bool moved = false;
    for (uint32_t j = 0; j < iso.count; ++j) {
      const uint32_t i = rising ? j : iso.count - 1 - j;
      if (!crossesValue(v0, value, iso.values[i]))
        continue;
      const float hit = isoCrossing(iso.values[i], t0, v0, t, value, cell0, slope0, samples, walkSteps);
      moved = moved || sampler.cell() != this->lastCell;
      const Vec3f gradient = sampler.pointVectorAt(this->shading->gradients, hit);
      const Vec3f rgb = shadeSurface(iso.colors[i], gradient, this->toEye, *this->shading);
      compositeBehind(color, {rgb.x, rgb.y, rgb.z, iso.opacity}, settings.terminationOpacity);
      if (color.w >= settings.terminationOpacity)
        return; // the ray ends here: no sample follows
    }
    // Back to the sample's own cell, for its gradient (from the corners: its record is not kept) and the next
    // walk.
    if (moved)
      sampler.at.enter(this->lastCell);
  }

  /// Where the ray leaves the mesh and comes back in before the sample at `tNext` (a gap between its boundary
  /// crossings, the last pastGap met) the field is not continuous: a surface between the last point and the
  /// gap, or between the gap and the sample, is found from points just inside the gap's ends, as at an
  /// interval's ends. `entered`: the face the ray comes back in by. True where the ray is then opaque.
  UVR_HOST_DEVICE bool isoAcrossGap(Vec4f &color, uint32_t &samples, uint32_t entered, float tNext,
                                    int walkSteps) {
    const float entry = intervals.gapEntry();
    if (!(entry > this->lastT))
      return false; // met already
    if (isoBeforeExit(color, samples, intervals.gapExit(), walkSteps))
      return true;
    this->lastValid = false;
    const float nudge = 0.01f * intervals.grid().spacing;
    if (!(entry + nudge < tNext))
      return false;
    sampler.enter(boundaryFaceCell(scene.mesh, entered));
    ++samples;
    float value;
    const bool inside = sampler.probe(entry + nudge, walkSteps, false, value);
    isoAt(color, samples, entry + nudge, value, inside, walkSteps);
    return false;
  }

  /// Where the ray left the mesh at `exit` after the last point, which lay inside: a surface between them is
  /// found from a point just inside the exit. True where the ray is then opaque.
  UVR_HOST_DEVICE bool isoBeforeExit(Vec4f &color, uint32_t &samples, float exit, int walkSteps) {
    const float tProbe = exit - 0.01f * intervals.grid().spacing;
    if (!this->lastValid || !(tProbe > this->lastT))
      return false;
    ++samples;
    float value;
    const bool inside = sampler.probe(tProbe, walkSteps, false, value);
    isoAt(color, samples, tProbe, value, inside, walkSteps);
    return color.w >= settings.terminationOpacity;
  }

  /// Where `cell`, a tet the walk passed on the ray, holds the crossing of `target` in [lo, hi]: the field
  /// is linear along the ray there, and the root closed-form. A root outside the bracket is another crossing,
  /// of a field that turns between the samples. `root` is set wherever the tet's field has a slope.
  UVR_HOST_DEVICE static bool rootInTet(const RayCell &cell, float target, float lo, float hi, float &root) {
    if (!cell.affine || cell.dvalue == 0.f)
      return false;
    root = cell.t + (target - cell.value) / cell.dvalue;
    const float slack = 1e-4f * (hi - lo); // rounding
    float w[4], lowest;
    cell.weightsAt(root, w, lowest);
    return lowest >= -kInsideTolerance && root >= lo - slack && root <= hi + slack;
  }

  /// Where the field crosses `target` between `t0` (value `v0`, in cell `cell0`, where it changes by `slope0`
  /// per unit t) and `t1` (`v1`), from the sampler in `t1`'s cell (or a nearer crossing's): in a tet the
  /// field is linear along the ray, so the root is closed-form once the tet that holds it is found (mostly
  /// one of the two); each step locates the best guess so far (that root, else regula falsi, every other step
  /// a bisection) and keeps the bracket around the crossing. The sampler ends in (or next to) its cell.
  UVR_HOST_DEVICE float isoCrossing(float target, float t0, float v0, float t1, float v1, uint32_t cell0,
                                    float slope0, uint32_t &samples, int walkSteps) {
    float lo = t0, hi = t1, fLo = v0 - target, fHi = v1 - target;
    float root;
    const bool inSampleTet = rootInTet(sampler.at, target, lo, hi, root);
    // The nearer crossing first: `t0`'s tet holds one where its line meets the target in the bracket (NaN
    // for other cells) and the point found lies in it, which a probe there from that tet tells. Where not,
    // and the sample's tet holds one, the sampler goes back there for its gradient.
    const float nearRoot = t0 + (target - v0) / slope0;
    if (cell0 != sampler.cell() && nearRoot >= lo && nearRoot <= (inSampleTet ? root : hi)) {
      float value;
      sampler.at.enter(cell0);
      ++samples;
      if (sampler.probe(nearRoot, walkSteps, false, value) && sampler.cell() == cell0)
        return nearRoot;
      if (inSampleTet) {
        ++samples;
        sampler.probe(root, walkSteps, false, value);
      }
    }
    if (inSampleTet)
      return clampf(root, lo, hi);
    for (int step = 0; step < kIsoRefineSteps; ++step) {
      if (rootInTet(sampler.at, target, lo, hi, root))
        return clampf(root, lo, hi);
      float t = lo - fLo * (hi - lo) / (fHi - fLo);
      if (sampler.at.affine && sampler.at.dvalue != 0.f)
        t = root;
      if ((step & 1) || !(lo < t && t < hi))
        t = 0.5f * (lo + hi);
      ++samples;
      float value;
      if (!sampler.probe(t, walkSteps, false, value))
        break;
      const float f = value - target;
      if (f == 0.f)
        return t;
      if ((f < 0.f) == (fLo < 0.f)) {
        lo = t;
        fLo = f;
      } else {
        hi = t;
        fHi = f;
      }
    }
    return lo - fLo * (hi - lo) / (fHi - fLo);
  }

  /// `c` lit where the field's gradient is `gradient`.
  UVR_HOST_DEVICE Vec4f shade(const Vec4f &c, Vec3f gradient) const {
    const Vec3f rgb = shadeColor({c.x, c.y, c.z}, gradient, this->toEye, *this->shading);
    return {rgb.x, rgb.y, rgb.z, c.w};
  }
};

/// Integrates one ray front to back (see RayMarch, RayIntervals and RaySampler). `hint` is a cell near the
/// ray's first sample (the neighbouring pixel's: rays are coherent), or kNoCell; it is updated to this ray's
/// first cell. The skipping modes march only between the ray's first and last boundary crossings, and not
/// through the gaps between them that lie outside the mesh, where `crossings` knows them. `trail`, where
/// the policy follows one, holds by grid point the previous ray's guesses at this ray's tets, and takes this
/// ray's at the next one's. `kShade`: light the samples by the field's gradient as `shading` says. `kIso`:
/// draw the isosurfaces `iso`, and light the samples where settings.shade.
template <class Sampling, bool kPreintegrate = false, bool kShade = false, bool kIso = false>
UVR_HOST_DEVICE inline RayResult
integrateRay(const SceneView &scene, const IntegratorSettings &settings, const Ray &ray, uint32_t &hint,
             const BoundaryCrossings &crossings, CellTrail trail = {},
             const ShadingSettings *shading = nullptr, const IsoSettings *iso = nullptr) {
  RayIntervals intervals(scene, settings, ray, crossings);
  if (intervals.none())
    return {};
  // Rejecting samples in empty space is part of space skipping: the modes without it locate every sample the
  // plain way, as the paper's reference ray marcher does. Where the crossings are listed, the occupancy grid
  // would only confirm that samples lie in cells.
  RaySampler<Sampling> sampler(scene, ray, hint, skipsSpace(settings.mode), !intervals.crossingsListed());
  if (intervals.entryCell() != kNoCell)
    sampler.enter(intervals.entryCell());
  // The next ray's grid starts where it enters the mesh bounds, as this one's does.
  sampler.follow(trail, settings.clip.empty() ? scene.partitions.rootBounds : settings.gridBounds,
                 intervals.grid().spacing);
  RayMarch<Sampling, kPreintegrate, kShade, kIso> march(scene, settings, intervals, sampler, hint, shading,
                                                        iso);
  intervals.forEach([&](float t0, float t1, float step) { return march.interval(t0, t1, step); },
                    [&](float &t0, float &t1) { return march.closingInterval(t0, t1); });
  return march.result;
}

} // namespace uvr
