// The sampler (Open VKL's split: volume, sampler, interval iterator): finds the cell holding a point on a ray
// and interpolates the field there, reading only the volume (mesh and acceleration data). Samples along a
// ray lie a cell or two apart, so each is walked to across faces from the last one's cell, with the seed grid
// and the BVH for walks that fail or would be long.
//
// The host and the GPU share the code; what only the host can afford (per-tet records, walks through cells
// other than tets, a trail of guesses from ray to ray) is chosen at compile time by a sampling policy, so
// that the GPU's kernels hold no code for it.
#pragma once

#include "accel/bvh.h"
#include "accel/volume_view.h"
#include "core/host_device.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "mesh/cell_neighbors.h"
#include "mesh/tet_affine.h"

#include <cstdint>

namespace uvr {

/// The GPU's sampling: tets from their corners, other cells tested one at a time, no trail.
struct DeviceSampling {
  static constexpr bool kTetRecords = false; ///< read the per-tet records where the volume has them
  static constexpr bool kCellWalks = false;  ///< walk across other cells than tets, given their adjacency
  static constexpr bool kTrail = false;      ///< follow a CellTrail from ray to ray
  /// Pre-integrating a cell field, visit the cells between two samples where they could show (RayMarch).
  static constexpr bool kCellsBetweenSamples = false;
  /// Drawing isosurfaces, locate the samples too by the sampler's one out-of-line probe (RayMarch::locate).
  static constexpr bool kIsoSamplesByProbe = true;
};

/// The GPU's sampling of a mesh with other cells than tets whose adjacency it holds: walks across them too.
/// A kernel of its own: the walks' code would cost a tet mesh's kernel registers and spills.
struct DeviceCellWalkSampling : DeviceSampling {
  static constexpr bool kCellWalks = true;
};

/// The host's sampling: all of the above. The GPU keeps no records (64 bytes per tet); its neighbouring rays
/// run at once, so there is no previous ray to learn from; and a second place that locates samples would
/// double its pre-integrating kernels' code.
struct HostSampling {
  static constexpr bool kTetRecords = true;
  static constexpr bool kCellWalks = true;
  static constexpr bool kTrail = true;
  static constexpr bool kCellsBetweenSamples = true;
  static constexpr bool kIsoSamplesByProbe = false;
};

/// The cell a ray's last sample lies in. For a tet, also the sample's barycentric weights and field with
/// their change per unit t along the ray: the next sample, a step on, is tested against the tet with a few
/// multiply-adds and no loads, and where it lies beyond, its weights name the face to walk across. For
/// another cell, its parametric coordinates and their change: the next sample's solve there starts from them.
struct RayCell {
  uint32_t cell = kNoCell;
  bool onRay = false;      ///< whether the ray passes through `cell`: where not, `cell` is a guess near it
  bool affine = false;     ///< whether the members below describe `cell` (a tet) on this ray
  bool parametric = false; ///< whether w[0..2] and dw[0..2] hold `cell`'s parametric coordinates and rate
  float t = 0.f;           ///< where they were evaluated
  float w[4], dw[4];
  float value, dvalue;

  /// Moves to `to`, a cell the ray passes through, with no weights known there yet.
  UVR_HOST_DEVICE void enter(uint32_t to) {
    cell = to;
    onRay = true;
    affine = false;
    parametric = false;
  }
  /// Where `affine`: the weights in `cell` of the point at `tNext` on the ray, and the face it lies furthest
  /// beyond (see smallestWeight), with its weight in `lowest`.
  UVR_HOST_DEVICE int weightsAt(float tNext, float weights[4], float &lowest) const {
    const float s = tNext - t;
    for (int i = 0; i < 4; ++i)
      weights[i] = w[i] + s * dw[i];
    return smallestWeight(weights, lowest);
  }
  /// Where `affine`: the field at `tNext` on the ray, as `cell` interpolates it.
  UVR_HOST_DEVICE float valueAt(float tNext) const { return value + (tNext - t) * dvalue; }
  /// Where the ray crosses `cell`'s boundary ahead of a point in it (`ahead`: where it leaves) or behind it
  /// (where it enters): for a tet exactly (the first weight ahead to fall to zero, the last behind to rise
  /// from it), for a hexahedron (`hex`) about (the parametric coordinates, carried along the ray by their
  /// rate, reaching 0 or 1); NaN where unknown (another cell, or no weights).
  UVR_HOST_DEVICE float crossingT(bool hex, bool ahead) const {
    // Behind, the nearest crossing of the ray reversed: the same minimum over the quotients negated.
    const float sign = ahead ? 1.f : -1.f;
    if (affine) {
      // Four independent quotients, then their minimum: the host's compiler divides them at once.
      float s[4];
      for (int i = 0; i < 4; ++i)
        s[i] = -sign * w[i] / dw[i];
      for (int i = 0; i < 4; ++i)
        s[i] = sign * dw[i] < 0.f ? s[i] : INFINITY;
      return t + sign * minf(minf(s[0], s[1]), minf(s[2], s[3]));
    }
    if (!parametric || !hex)
      return NAN;
    float s = INFINITY;
    for (int i = 0; i < 3; ++i)
      s = dw[i] != 0.f ? minf(s, sign * ((sign * dw[i] < 0.f ? 0.f : 1.f) - w[i]) / dw[i]) : s;
    return t + sign * s;
  }
};

/// Per index on the sample grid (see RaySampler::follow), a guess at the tet holding a CPU thread's next
/// ray's sample: each ray reads its entries and then writes there, for the next ray, the tet its own sample
/// lies in or, where the next ray's point of the same index lies beyond a face of it, the neighbour across
/// (see likelyTet). Neighbouring rays pass a fraction of a cell apart, so a walk from such a guess mostly
/// ends at its first tet, far more often than one from the tet the previous ray found, and whether it does
/// is no longer a coin toss for the branch predictor. One buffer serves a thread's rays in turn (pixels in
/// serpentine order), and an entry left by an older ray is only a worse guess.
struct CellTrail {
  uint32_t *cells = nullptr; ///< kNoCell where the ray found no tet
  uint32_t size = 0;
  const Ray *next = nullptr; ///< the ray that reads the entries this one writes, or null
};

/// The tet that most likely holds `p`, a point a fraction of a cell from one in `tet`: `tet`, or where `p`
/// lies beyond a face, the tet (not another cell) across the face it lies furthest beyond. Computed without a
/// branch, since which way it goes is a coin toss. Host only: it reads the records.
inline uint32_t likelyTet(const VolumeView &volume, uint32_t tet, Vec3f p) {
  float w[4], value;
  volume.tetAffine[tet].at(p, w, value);
  const float lowest = minf(minf(w[0], w[1]), minf(w[2], w[3]));
  // The face by a mask, not smallestWeight, whose choice the compiler turns into a branch here: one that
  // mispredicts half the time. Bit 3 stands for face 3, and where a weight is NaN (a flat tet), for any.
  const unsigned lowestFaces =
      unsigned(w[0] == lowest) | unsigned(w[1] == lowest) << 1 | unsigned(w[2] == lowest) << 2 | 8u;
  const uint32_t across = volume.tetNeighbors[4 * uint64_t(tet) + uint64_t(__builtin_ctz(lowestFaces))];
  const uint32_t moves =
      0u - (uint32_t(lowest < -kInsideTolerance) & uint32_t(across < volume.mesh.tetCount));
  return tet ^ ((tet ^ across) & moves);
}

/// The tet, of those `across` the faces of a tet, that a walk towards a point with weights `w` crosses: the
/// face the point lies furthest beyond (`beyond`); where that is the mesh's boundary and the walk follows a
/// ray (`alongRay`), the face the ray leaves by, whose weights change by `dw` along it. A walk from a tet on
/// the ray thus goes on around a concavity, where the point, inside the mesh, lies beyond the boundary as
/// seen from a tet on the way; a walk from a guess gives up at once.
UVR_HOST_DEVICE inline uint32_t nextTet(Index4 across, int beyond, const float w[4], const float dw[4],
                                        bool alongRay) {
  const uint32_t next = across[beyond];
  return next != kNoCell || !alongRay ? next : across[rayExitFace(w, dw, beyond)];
}

/// Tet `tet`'s record where the policy reads them and the volume has them, else null (the walk then reads
/// the corners). The walk's next tet, or the next sample's, is one of the neighbours `across`: fetching
/// their records while this one is evaluated hides most of the miss on the next.
template <class Sampling>
UVR_HOST_DEVICE UVR_HOST_INLINE const TetAffine *tetRecord(const VolumeView &volume, uint32_t tet,
                                                           Index4 across) {
  if constexpr (Sampling::kTetRecords) {
    const TetAffine *affine = volume.tetAffine ? volume.tetAffine + tet : nullptr;
    if (affine) {
      for (int i = 0; i < 4; ++i)
        if (across[i] < volume.mesh.tetCount)
          __builtin_prefetch(volume.tetAffine + across[i]);
    }
    return affine;
  } else {
    return nullptr;
  }
}

/// The barycentric weights `w` of `p` in a tet and their change `dw` per unit step along `direction`: from
/// its record `affine`, which also gives the field there and its change (`value`, `slope`), or where that is
/// null, from its corners `v`. False for a flat tet.
template <class Sampling>
UVR_HOST_DEVICE UVR_HOST_INLINE bool tetWeightsAlong(const MeshView &mesh, const TetAffine *affine, Index4 v,
                                                     Vec3f p, Vec3f direction, float w[4], float dw[4],
                                                     float &value, float &slope) {
  if constexpr (Sampling::kTetRecords) { // records are host-only: the GPU's code must not name along()
    if (affine)
      return affine->along(p, direction, w, dw, value, slope);
  }
  return tetBarycentricsAlong(mesh.points[v.x], mesh.points[v.y], mesh.points[v.z], mesh.points[v.w], p,
                              direction, w, dw);
}

/// Where a walk through tets stopped at another cell (see walkTets): that cell, and the tets it stepped
/// through.
struct WalkHandover {
  uint32_t cell = kNoCell;
  int steps = 0;
};

/// Steps through tets towards the sample at `t` on `ray`, from `start` across the face the sample lies
/// furthest beyond (see nextTet; `alongRay`: the ray passes through `start`), as long as that is a tet; on
/// success `at` describes the tet holding the sample and `value` is the field there. Gives up after
/// `maxSteps` tets; where the next cell is another than a tet (linkTetsToOtherCells), stops and names it in
/// `handover`, if given.
template <class Sampling>
UVR_HOST_DEVICE UVR_HOST_INLINE bool walkTets(const VolumeView &volume, const Ray &ray, float t,
                                              uint32_t start, bool alongRay, int maxSteps, RayCell &at,
                                              float &value, WalkHandover *handover = nullptr) {
  const MeshView &mesh = volume.mesh;
  uint32_t current = start;
  int step = 0;
  float w[4];
  if (at.affine && at.cell == start) {
    const Index4 across = Index4::load(volume.tetNeighbors + 4 * uint64_t(current));
    float lowest;
    const int exit = at.weightsAt(t, w, lowest);
    if (lowest >= -kInsideTolerance) {
      value = at.valueAt(t);
      return true;
    }
    current = nextTet(across, exit, w, at.dw, alongRay);
    step = 1;
  }
  const Vec3f p = ray.at(t);
  for (; step < maxSteps && current < mesh.tetCount; ++step) {
    // Read before the weights, not once the face to cross is known: the next tet is then at hand.
    const Index4 across = Index4::load(volume.tetNeighbors + 4 * uint64_t(current));
    const TetAffine *affine = tetRecord<Sampling>(volume, current, across);
    // The corners only where no record holds the tet: read anyway, they were another line missed per step.
    const Index4 v = affine ? Index4{} : Index4::load(mesh.tets + 4 * uint64_t(current));
    float dw[4], slope = 0.f;
    if (!tetWeightsAlong<Sampling>(mesh, affine, v, p, ray.direction, w, dw, value, slope))
      return false;
    float lowest;
    const int exit = smallestWeight(w, lowest);
    if (lowest >= -kInsideTolerance) {
      if (!affine) { // else the record gave the value and its slope with the weights
        if (mesh.cellCentered) {
          value = mesh.values[current];
        } else {
          const float v0 = mesh.values[v.x], v1 = mesh.values[v.y], v2 = mesh.values[v.z],
                      v3 = mesh.values[v.w];
          value = w[0] * v0 + w[1] * v1 + w[2] * v2 + w[3] * v3;
          slope = dw[0] * v0 + dw[1] * v1 + dw[2] * v2 + dw[3] * v3;
        }
      }
      at.cell = current;
      at.onRay = true;
      at.affine = true;
      at.parametric = false;
      at.t = t;
      for (int i = 0; i < 4; ++i) {
        at.w[i] = w[i];
        at.dw[i] = dw[i];
      }
      at.value = value;
      at.dvalue = slope;
      return true;
    }
    current = nextTet(across, exit, w, dw, alongRay);
  }
  // Where a walk along the ray left the mesh, so did the ray: later walks from `at` stop at the boundary,
  // rather than follow the ray out again for every sample in the empty space beyond.
  if (alongRay && current == kNoCell)
    at.onRay = false;
  if (handover && current != kNoCell && current >= mesh.tetCount)
    *handover = {current, step};
  return false;
}

/// How far beyond a triangle's plane, in units of the cell's size, a point may lie and still be tested
/// against the cell: rounding, which the cell's test (kInsideTolerance) allows for too.
constexpr float kTrianglePlaneSlack = 1e-4f;

/// How far beyond a hexahedron's face, in parametric units, a walk takes the last sample's coordinates
/// carried along the ray at their word: their error grows with the square of the distance and with the
/// cell's distortion; a wrong guess costs a step back.
constexpr float kHexLeaveUnsolved = 0.01f;

/// Steps through cells of any type towards the sample at `t` on `ray`, from `start`: tets by walkTets (with
/// `alongRay` where the walk starts in one), which hands back where it reaches another cell. A hexahedron is
/// solved for the sample's parametric coordinates, which name the face to cross where it lies outside.
/// Another cell is solved only where the sample lies within about all its faces' planes, else left across
/// the face whose plane it lies furthest beyond. Gives up after `maxSteps` cells.
template <class Sampling>
UVR_HOST_DEVICE inline bool walkCells(const VolumeView &volume, const Ray &ray, float t, uint32_t start,
                                      bool alongRay, int maxSteps, RayCell &at, float &value) {
  const MeshView &mesh = volume.mesh;
  const Vec3f p = ray.at(t);
  const uint64_t firstHex = mesh.tetCount + mesh.pyramidCount + mesh.wedgeCount;
  uint32_t current = start;
  for (int step = 0; step < maxSteps && current != kNoCell; ++step) {
    if (current < mesh.tetCount) {
      WalkHandover handover;
      if (!volume.tetNeighbors)
        return false;
      if (walkTets<Sampling>(volume, ray, t, current, alongRay && step == 0, maxSteps - step, at, value,
                             &handover))
        return true;
      if (handover.cell == kNoCell)
        return false;
      current = handover.cell;
      step += handover.steps;
      continue;
    }
    const uint64_t other = uint64_t(current) - mesh.tetCount;
    RaySolve along;
    along.direction = ray.direction;
    if ((along.warm = at.parametric && at.cell == current))
      along.start = Vec3f{at.w[0], at.w[1], at.w[2]} + Vec3f{at.dw[0], at.dw[1], at.dw[2]} * (t - at.t);
    bool inside = false;
    int face;
    float beyond;
    if (current >= firstHex) {
      // Where the last sample's coordinates, carried along the ray, lie beyond a face, this sample most
      // likely does too: the walk leaves without a solve, and on its way back, should it come back, solves.
      face = hexFaceBeyond(along.start, beyond);
      if (!along.warm || step > 0 || beyond <= kHexLeaveUnsolved) {
        along.anywhere = true;
        inside =
            sampleIsoparametric<8>(mesh, mesh.hexes + 8 * (current - firstHex), current, p, value, &along);
        face = hexFaceBeyond(along.start, beyond);
      }
    } else {
      const bool pyramid = other < mesh.pyramidCount;
      float beyondTriangles;
      face = furthestFace(volume.cellFacePlanes, other, p, pyramid ? kPyramidTriangles : kWedgeTriangles,
                          beyond, beyondTriangles);
      // A quad of a distorted cell is not planar: near its plane, the cell's own test decides. A triangle's
      // plane does at once.
      if (beyond <= 0.25f && beyondTriangles <= kTrianglePlaneSlack)
        inside = pyramid ? sampleIsoparametric<5>(mesh, mesh.pyramids + 5 * other, current, p, value, &along)
                         : sampleIsoparametric<6>(mesh, mesh.wedges + 6 * (other - mesh.pyramidCount),
                                                  current, p, value, &along);
    }
    if (inside) {
      at.enter(current);
      at.parametric = true;
      at.t = t;
      at.w[0] = along.start.x, at.w[1] = along.start.y, at.w[2] = along.start.z;
      at.dw[0] = along.rate.x, at.dw[1] = along.rate.y, at.dw[2] = along.rate.z;
      return true;
    }
    current = volume.cellNeighbors[kMaxCellFaces * other + uint64_t(face)];
  }
  return false;
}

/// Finds the cell holding the sample at `t` on `ray` and returns the field there. Where `guess` (the
/// tet the neighbouring ray expects this sample in, see CellTrail) is a tet other than `at`'s and the sample
/// is not in `at`'s, a short walk from `guess` comes first. Else the walk starts from `at` (the previous
/// sample's cell), or, where the sample lies `far` from it (a step longer than a seed voxel) or there is
/// none, from the seed of the sample's voxel. `walkSteps` bounds a walk from `at`: about 8 per fixed step,
/// since samples lie a cell or two apart. With `skipEmpty`, points in empty space are rejected without the
/// BVH: with `clearVoxels` too by the occupancy grid at once, or where the walk fails, by the boundary faces'
/// parity; and a point the parity leaves inside (the walk left the mesh through a concavity, or ran out of
/// steps) is walked to again from a cell near it (SeedGridView::startNear), so that the BVH, a long divergent
/// query on a GPU, is left for what neither walk finds. Without `skipEmpty` a failed walk goes to the BVH, as
/// in a plain ray marcher. With `pastMesh`, the sample lies past the ray's last crossing out of the mesh: a
/// cell there is one of the boundary's, bulging past the triangles the crossings were found on (a quad's
/// bilinear face), so the first walk finds it or no cell holds the sample, and nothing slower is tried.
template <class Sampling>
UVR_HOST_DEVICE UVR_HOST_INLINE bool
locateSample(const VolumeView &volume, bool skipEmpty, bool clearVoxels, const Ray &ray, float t,
             int walkSteps, bool far, uint32_t guess, RayCell &at, float &value, bool pastMesh = false) {
  const Vec3f p = ray.at(t);
  if (skipEmpty && clearVoxels && !volume.occupancy.mayHoldCell(p))
    return false;
  // Four tets: most walks from a guess end at the first, and one that fails falls back on the ray's own. A
  // test of the ray's own tet first would seldom find the sample where the guess does not.
  if (guess != kNoCell && guess != at.cell && volume.tetNeighbors &&
      walkTets<Sampling>(volume, ray, t, guess, false, 4, at, value))
    return true;
  // A walk from `start`; a cell other than a tet is tested alone where the policy has no walks for it.
  auto locateFrom = [&](uint32_t start, int steps) {
    const bool alongRay = start == at.cell && at.onRay;
    if constexpr (Sampling::kCellWalks) {
      if (volume.cellNeighbors)
        return walkCells<Sampling>(volume, ray, t, start, alongRay, steps, at, value);
    }
    if (volume.tetNeighbors && start < volume.mesh.tetCount)
      return walkTets<Sampling>(volume, ray, t, start, alongRay, steps, at, value);
    if (!sampleCell(volume.mesh, start, p, value))
      return false;
    at.enter(start);
    return true;
  };
  const uint32_t seed = far || at.cell == kNoCell ? volume.seeds.seedAt(p) : kNoCell;
  const uint32_t start = seed != kNoCell ? seed : at.cell;
  if (start != kNoCell && locateFrom(start, seed != kNoCell ? kSeedWalkSteps : walkSteps))
    return true;
  if (pastMesh)
    return false;
  if (skipEmpty) {
    if (volume.seeds.outsideMesh(volume.mesh, p))
      return false;
    const uint32_t nearby = volume.seeds.startNear(p);
    if (nearby != kNoCell && nearby != start && locateFrom(nearby, kSeedWalkSteps))
      return true;
  }
  return findCell(volume.bvh, p, [&](uint32_t candidate) {
    if (candidate == start || !sampleCell(volume.mesh, candidate, p, value))
      return false;
    at.enter(candidate);
    return true;
  });
}

/// Per-point vectors interpolated by the shape functions of the cell of N corners `v`, at parametric
/// coordinates `r`.
template <int N>
UVR_HOST_DEVICE inline Vec3f interpolateAt(const Vec3f *perPoint, const uint32_t *v, Vec3f r) {
  ShapeFunctions<N> s;
  evaluateShape(r, s);
  Vec3f sum{};
  for (int i = 0; i < N; ++i)
    sum = sum + perPoint[v[i]] * s.value[i];
  return sum;
}

/// A per-point vector (the field's gradient) interpolated to `p`, the point at `t` on a ray, in `at.cell`,
/// the cell the sampler found it in: a tet by the weights the walk carries (or, where it found the tet
/// another way, its barycentric weights), another cell by its shape functions at the parametric coordinates
/// the walk solved for at `t` (where it did) or else solved for here, or where that solve fails, the mean of
/// its corners.
UVR_HOST_DEVICE inline Vec3f interpolatePointVectors(const MeshView &mesh, const Vec3f *perPoint,
                                                     const RayCell &at, Vec3f p, float t) {
  int count;
  const uint32_t *v = cellCorners(mesh, at.cell, count);
  if (count == 4) {
    float w[4];
    if (at.affine) {
      for (int i = 0; i < 4; ++i)
        w[i] = at.w[i] + (t - at.t) * at.dw[i];
    } else if (!tetBarycentrics(mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]], p,
                                w)) {
      w[0] = w[1] = w[2] = w[3] = 0.25f;
    }
    return perPoint[v[0]] * w[0] + perPoint[v[1]] * w[1] + perPoint[v[2]] * w[2] + perPoint[v[3]] * w[3];
  }
  if (at.parametric && at.t == t) {
    // The walk solved for this very point.
    const Vec3f r{at.w[0], at.w[1], at.w[2]};
    return count == 5   ? interpolateAt<5>(perPoint, v, r)
           : count == 6 ? interpolateAt<6>(perPoint, v, r)
                        : interpolateAt<8>(perPoint, v, r);
  }
  float weights[8];
  bool solved = false;
  if (count == 5) {
    ShapeFunctions<5> s;
    if ((solved = isoparametricWeights<5>(mesh.points, v, p, s)))
      for (int i = 0; i < 5; ++i)
        weights[i] = s.value[i];
  } else if (count == 6) {
    ShapeFunctions<6> s;
    if ((solved = isoparametricWeights<6>(mesh.points, v, p, s)))
      for (int i = 0; i < 6; ++i)
        weights[i] = s.value[i];
  } else {
    ShapeFunctions<8> s;
    if ((solved = isoparametricWeights<8>(mesh.points, v, p, s)))
      for (int i = 0; i < 8; ++i)
        weights[i] = s.value[i];
  }
  Vec3f sum{};
  for (int i = 0; i < count; ++i)
    sum = sum + perPoint[v[i]] * (solved ? weights[i] : 1.f / float(count));
  return sum;
}

/// Samples one ray's field at growing t: what the sampler carries along a ray (the cell of its last sample,
/// and on the host the trail) around locateSample.
template <class Sampling> struct RaySampler {
  const VolumeView &volume;
  const Ray &ray;
  bool skipEmpty;   ///< see locateSample
  bool clearVoxels; ///< likewise
  RayCell at;
  CellTrail trail;
  bool predict = false;   ///< whether the entries written are guesses at the next ray's tets (likelyTet)
  float nextOrigin = 0.f; ///< where the next ray's sample grid starts
  float spacing = 0.f;    ///< and its spacing, this ray's

  /// A sampler for `ray` whose first walk starts at `near` (kNoCell: at a seed).
  UVR_HOST_DEVICE RaySampler(const VolumeView &volume, const Ray &ray, uint32_t near, bool skipEmpty,
                             bool clearVoxels)
      : volume(volume), ray(ray), skipEmpty(skipEmpty), clearVoxels(clearVoxels) {
    at.cell = near;
  }

  /// Follows `trail`, indexed by point on the sample grid: t = tEnter + k * gridSpacing, from where a ray
  /// enters `gridBounds`. Only where the policy has a trail.
  UVR_HOST_DEVICE void follow(const CellTrail &cells, const Box3f &gridBounds, float gridSpacing) {
    if constexpr (Sampling::kTrail) {
      trail = cells;
      spacing = gridSpacing;
      float nextExit;
      predict = trail.next && volume.tetAffine &&
                intersectBox(*trail.next, gridBounds, 0.f, INFINITY, nextOrigin, nextExit);
    }
  }

  /// Moves to `cell`, one the ray enters the mesh by.
  UVR_HOST_DEVICE void enter(uint32_t cell) { at.enter(cell); }
  /// The cell of the last sample located, or the one near it the sampler started from.
  UVR_HOST_DEVICE uint32_t cell() const { return at.cell; }

  /// A per-point vector interpolated to the last sample located, at `t` (see interpolatePointVectors).
  UVR_HOST_DEVICE Vec3f pointVectorAt(const Vec3f *perPoint, float t) const {
    return interpolatePointVectors(volume.mesh, perPoint, at, ray.at(t), t);
  }

  /// The field at `t` into `value`, anywhere along the ray (a point between samples: the sampler moves to
  /// its cell, and the trail is left as it is); false where no cell holds it. `pastMesh` as locateSample
  /// takes it. Out of line on the GPU: the isosurfaces' search probes at several places.
  UVR_HOST_DEVICE UVR_DEVICE_NOINLINE bool probe(float t, int walkSteps, bool far, float &value,
                                                 bool pastMesh = false) {
    return locateSample<Sampling>(volume, skipEmpty, clearVoxels, ray, t, walkSteps, far, kNoCell, at, value,
                                  pastMesh);
  }

  /// The field at `t`, grid point `k`, into `value`; false where no cell holds the sample. `walkSteps` and
  /// `far` and `pastMesh` as locateSample takes them.
  UVR_HOST_DEVICE UVR_HOST_INLINE bool sample(float t, float k, int walkSteps, bool far, float &value,
                                              bool pastMesh) {
    if constexpr (!Sampling::kTrail) {
      return locateSample<Sampling>(volume, skipEmpty, clearVoxels, ray, t, walkSteps, far, kNoCell, at,
                                    value, pastMesh);
    } else {
      // Compared as floats: k may lie past what a uint32_t holds where the trail ends.
      const bool trailed = k < float(trail.size);
      const uint32_t index = trailed ? uint32_t(k) : 0;
      const bool located =
          locateSample<Sampling>(volume, skipEmpty, clearVoxels, ray, t, walkSteps, far,
                                 trailed ? trail.cells[index] : kNoCell, at, value, pastMesh);
      if (trailed) {
        uint32_t cell = located && at.cell < volume.mesh.tetCount ? at.cell : kNoCell;
        if (predict && cell != kNoCell)
          cell = likelyTet(volume, cell, trail.next->at(nextOrigin + k * spacing));
        trail.cells[index] = cell;
      }
      return located;
    }
  }
};

} // namespace uvr
