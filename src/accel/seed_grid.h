// Where point location starts for a sample far from the last one, and which samples lie provably outside the
// mesh. Per voxel of a coarse grid over the mesh bounds: a seed, a cell holding the voxel's centre; and, for
// tet meshes, the boundary faces (tet faces with no neighbour) that meet the voxel, each with the octants of
// the voxel it meets.
//
// A walk from the previous sample's cell crosses every cell in between, so with steps of many cells (adaptive
// sampling) it would cost as much as the samples it saves; from the seed it crosses a cell or two. And a
// sample whose walk leaves the mesh would take a BVH query that, near the surface, mostly finds nothing and
// keeps a GPU warp waiting; the parity of the boundary faces between the voxel's centre and the sample says
// "outside" at the cost of a few triangle tests. Flat arrays, usable on host and device.
#pragma once

#include "accel/voxel_grid.h"
#include "core/host_device.h"
#include "core/storage.h"
#include "core/vec.h"
#include "mesh/cell.h"
#include "mesh/mesh_view.h"

#include <cstdint>
#include <vector>

namespace uvr {

/// A walk from a seed crosses a cell or two; a few more leave room for slivers.
constexpr int kSeedWalkSteps = 8;

/// Whether the segment q0-q1 crosses triangle abc: 1 if it does, 0 if not, -1 where an end lies within
/// `tolerance` of the triangle's plane or the crossing within a relative 1e-4 of an edge (too close to call).
UVR_HOST_DEVICE inline int segmentCrossesTriangle(Vec3f q0, Vec3f q1, Vec3f a, Vec3f b, Vec3f c,
                                                  float tolerance) {
  const Vec3f n = cross(b - a, c - a);
  const float d0 = dot(n, q0 - a), d1 = dot(n, q1 - a);
  const float planeTolerance = tolerance * length(n);
  if ((d0 > planeTolerance && d1 > planeTolerance) || (d0 < -planeTolerance && d1 < -planeTolerance))
    return 0;
  if (!(fabsf(d0) > planeTolerance && fabsf(d1) > planeTolerance))
    return -1; // also a flat triangle (n = 0)
  const Vec3f x = q0 + (q1 - q0) * (d0 / (d0 - d1));
  // Twice the signed areas of x with each edge, along n: all positive inside.
  const float w0 = dot(n, cross(b - x, c - x)), w1 = dot(n, cross(c - x, a - x)),
              w2 = dot(n, cross(a - x, b - x));
  const float edgeTolerance = 1e-4f * dot(n, n);
  if (w0 < -edgeTolerance || w1 < -edgeTolerance || w2 < -edgeTolerance)
    return 0;
  return w0 > edgeTolerance && w1 > edgeTolerance && w2 > edgeTolerance ? 1 : -1;
}

/// The corners of boundary face `face`, numbered 4 * tet + i for the face opposite corner i.
UVR_HOST_DEVICE inline void tetFaceCorners(const MeshView &mesh, uint32_t face, Vec3f &a, Vec3f &b,
                                           Vec3f &c) {
  const uint32_t *v = mesh.tets + 4 * uint64_t(face >> 2);
  const uint32_t i = face & 3u;
  a = mesh.points[v[(i + 1) & 3u]];
  b = mesh.points[v[(i + 2) & 3u]];
  c = mesh.points[v[(i + 3) & 3u]];
}

/// The bit of the octant around `centre` that holds `p`: 1 << (x + 2y + 4z), x being 1 on the upper side.
UVR_HOST_DEVICE inline uint32_t octantBit(Vec3f centre, Vec3f p) {
  return 1u << ((p.x >= centre.x ? 1 : 0) + (p.y >= centre.y ? 2 : 0) + (p.z >= centre.z ? 4 : 0));
}

struct SeedGridView {
  const uint32_t *seeds = nullptr; ///< per voxel, x fastest; kNoCell where no cell holds the centre
  /// Per voxel and one more, where its faces begin in `boundaryFaces`; null where they are not listed (meshes
  /// with other cells than tets).
  const uint32_t *boundaryStart = nullptr;
  const uint32_t *boundaryFaces = nullptr;  ///< 4 * tet + i, face i being the one opposite corner i
  const uint8_t *boundaryOctants = nullptr; ///< per listed face, a bit per octant of the voxel it meets
  VoxelGrid grid;

  /// The seed of the voxel holding `p`, or kNoCell (also outside the grid, and without a grid).
  UVR_HOST_DEVICE uint32_t seedAt(Vec3f p) const {
    int x, y, z;
    return seeds && grid.voxelOf(p, x, y, z) ? seeds[grid.index(x, y, z)] : kNoCell;
  }

  /// A cell to walk to `p` from: its voxel's seed; in a voxel whose centre lies outside the mesh, the tet of
  /// the lowest-numbered boundary face meeting the octant of `p` (the lowest, so that the order the build
  /// listed them in does not matter); kNoCell where there is neither.
  UVR_HOST_DEVICE uint32_t startNear(Vec3f p) const {
    int x, y, z;
    if (!seeds || !grid.voxelOf(p, x, y, z))
      return kNoCell;
    const uint64_t voxel = grid.index(x, y, z);
    if (seeds[voxel] != kNoCell || !boundaryStart)
      return seeds[voxel];
    const uint32_t octant = octantBit(grid.centre(x, y, z), p);
    uint32_t lowest = kNoCell;
    for (uint32_t i = boundaryStart[voxel]; i < boundaryStart[voxel + 1]; ++i)
      if ((boundaryOctants[i] & octant) && boundaryFaces[i] < lowest)
        lowest = boundaryFaces[i];
    return lowest == kNoCell ? kNoCell : lowest >> 2;
  }

  /// True only where `p` lies in no cell of `mesh`: its voxel's centre is inside exactly when it has a seed,
  /// and each boundary face that the segment from there to `p` crosses flips that. The segment lies in the
  /// octant of the voxel that holds `p`, so only the faces meeting that octant are tested. False where that
  /// is not known (no face lists, outside the grid, a crossing too close to call).
  UVR_HOST_DEVICE bool outsideMesh(const MeshView &mesh, Vec3f p) const {
    int x, y, z;
    if (!boundaryStart || !grid.voxelOf(p, x, y, z))
      return false;
    const uint64_t voxel = grid.index(x, y, z);
    const Vec3f from = grid.centre(x, y, z);
    const float tolerance = 1e-4f * grid.voxelEdge();
    const uint32_t octant = octantBit(from, p);
    bool inside = seeds[voxel] != kNoCell;
    for (uint32_t i = boundaryStart[voxel]; i < boundaryStart[voxel + 1]; ++i) {
      if (!(boundaryOctants[i] & octant))
        continue;
      Vec3f a, b, c;
      tetFaceCorners(mesh, boundaryFaces[i], a, b, c);
      const int crossing = segmentCrossesTriangle(from, p, a, b, c, tolerance);
      if (crossing < 0)
        return false;
      inside ^= crossing == 1;
    }
    return !inside;
  }
};

template <typename Storage> struct SeedGridArrays {
  template <typename T> using Array = typename Storage::template Array<T>;
  Array<uint32_t> seeds;
  Array<uint32_t> boundaryStart, boundaryFaces; ///< empty where not listed
  Array<uint8_t> boundaryOctants;               ///< one per listed face
  VoxelGrid grid;

  SeedGridView view() const {
    return {dataOrNull(seeds), dataOrNull(boundaryStart), boundaryFaces.data(), boundaryOctants.data(), grid};
  }
  template <typename A, typename B, typename F> static void forEachMember(A &a, B &b, F &&f) {
    f(a.seeds, b.seeds);
    f(a.boundaryStart, b.boundaryStart);
    f(a.boundaryFaces, b.boundaryFaces);
    f(a.boundaryOctants, b.boundaryOctants);
    f(a.grid, b.grid);
  }
};
using SeedGrid = SeedGridArrays<HostStorage>;

/// About `voxelsPerCell` voxels per cell over the mesh bounds, 4 bytes each and 4 more for the face lists,
/// whose entries take 5 bytes.
/// The default keeps a walk from a seed to a few cells on the brain meshes, whose cells fill about half their
/// bounds.
constexpr float kDefaultSeedVoxelsPerCell = 0.5f;

/// The grid with its seeds (each voxel's is the lowest-numbered cell holding its centre, so that any build
/// order gives the same grid) and, for a mesh of tets alone with `tetNeighbors` given, its boundary faces.
SeedGrid buildSeedGrid(const MeshView &mesh, const uint32_t *tetNeighbors,
                       float voxelsPerCell = kDefaultSeedVoxelsPerCell);

/// Whether the grid lists boundary faces for `mesh`: tets alone, few enough to number their faces in 32 bits.
UVR_HOST_DEVICE inline bool listsBoundaryFaces(const MeshView &mesh) {
  return mesh.cellCount() == mesh.tetCount && mesh.tetCount <= (uint64_t(1) << 30);
}

/// Calls `visit(x, y, z)` for the voxels of `grid` that `span` picks along each axis for `box`:
/// `span(lo, hi, first, last)` takes the box's extent in voxel units and gives an index range, clamped here.
template <typename Span, typename Visit>
UVR_HOST_DEVICE void forEachVoxelIn(const VoxelGrid &grid, const Box3f &box, Span &&span, Visit &&visit) {
  const int count[3] = {grid.nx, grid.ny, grid.nz};
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) {
    span((box.lower[a] - grid.origin[a]) * grid.voxelsPerUnit[a],
         (box.upper[a] - grid.origin[a]) * grid.voxelsPerUnit[a], first[a], last[a]);
    first[a] = first[a] < 0 ? 0 : first[a];
    last[a] = last[a] > count[a] - 1 ? count[a] - 1 : last[a];
  }
  for (int z = first[2]; z <= last[2]; ++z)
    for (int y = first[1]; y <= last[1]; ++y)
      for (int x = first[0]; x <= last[0]; ++x)
        visit(x, y, z);
}

/// Calls `offer(voxel)` for each voxel of `grid` whose centre lies in cell `c`.
template <typename Offer>
UVR_HOST_DEVICE void forEachSeededVoxel(const MeshView &mesh, uint64_t c, const VoxelGrid &grid,
                                        Offer &&offer) {
  // Voxel i's centre is at i + 1/2 in voxel units: the indices whose centres lie within the box, with a
  // hundredth of a voxel's slack against rounding (the test is exact).
  auto centresWithin = [](float lo, float hi, int &first, int &last) {
    first = int(ceilf(lo - 0.51f));
    last = int(floorf(hi - 0.49f));
  };
  forEachVoxelIn(grid, cellBounds(mesh, c), centresWithin, [&](int x, int y, int z) {
    if (cellContains(mesh, c, grid.centre(x, y, z)))
      offer(grid.index(x, y, z));
  });
}

/// Whether triangle abc meets the box of centre `centre` and half extent `half`: no separating axis among
/// the box's three, the triangle's normal and the nine crossings of an edge with a box axis.
UVR_HOST_DEVICE inline bool triangleMeetsBox(Vec3f a, Vec3f b, Vec3f c, Vec3f centre, Vec3f half) {
  const Vec3f v[3] = {a - centre, b - centre, c - centre};
  // Separated along `axis` when the triangle's projection lies beyond the box's radius there.
  auto separatedAlong = [&](Vec3f axis) {
    const float p0 = dot(axis, v[0]), p1 = dot(axis, v[1]), p2 = dot(axis, v[2]);
    const float radius = half.x * fabsf(axis.x) + half.y * fabsf(axis.y) + half.z * fabsf(axis.z);
    return minf(p0, minf(p1, p2)) > radius || maxf(p0, maxf(p1, p2)) < -radius;
  };
  const Vec3f boxAxes[3] = {{1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}};
  const Vec3f edges[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  for (const Vec3f &axis : boxAxes)
    if (separatedAlong(axis))
      return false;
  if (separatedAlong(cross(edges[0], edges[1])))
    return false;
  for (const Vec3f &edge : edges)
    for (const Vec3f &axis : boxAxes)
      if (separatedAlong(cross(edge, axis)))
        return false;
  return true;
}

/// Calls `offer(voxel, octants)` for each voxel of `grid` that boundary face `face` (4 * tet + i) meets, with
/// a bit per octant of the voxel it meets (see octantBit). Octants are widened by a hundredth of a voxel, so
/// that rounding never leaves out one the face touches.
template <typename Offer>
UVR_HOST_DEVICE void forEachBoundaryVoxel(const MeshView &mesh, uint32_t face, const VoxelGrid &grid,
                                          Offer &&offer) {
  Vec3f a, b, c;
  tetFaceCorners(mesh, face, a, b, c);
  Box3f box;
  box.extend(a);
  box.extend(b);
  box.extend(c);
  auto voxelsReached = [](float lo, float hi, int &first, int &last) {
    first = int(floorf(lo - 0.01f));
    last = int(floorf(hi + 0.01f));
  };
  const Vec3f quarter = grid.voxelSize * 0.25f, half = grid.voxelSize * 0.26f;
  forEachVoxelIn(grid, box, voxelsReached, [&](int x, int y, int z) {
    const Vec3f centre = grid.centre(x, y, z);
    uint32_t octants = 0;
    for (uint32_t o = 0; o < 8; ++o) {
      const Vec3f octantCentre = {centre.x + ((o & 1u) ? quarter.x : -quarter.x),
                                  centre.y + ((o & 2u) ? quarter.y : -quarter.y),
                                  centre.z + ((o & 4u) ? quarter.z : -quarter.z)};
      if (triangleMeetsBox(a, b, c, octantCentre, half))
        octants |= 1u << o;
    }
    if (octants)
      offer(grid.index(x, y, z), octants);
  });
}

} // namespace uvr
