// The tet walk that locates samples along a ray, with the weights a ray carries from sample to sample.
#include "accel/sampler.h"
#include "mesh/cell.h"
#include "mesh/cell_neighbors.h"
#include "mesh/mesh.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_affine.h"
#include "mesh/tet_neighbors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

using namespace uvr;

namespace {

/// The first cell holding `p`, found by testing every cell; kNoCell where none does.
uint32_t cellHolding(const MeshView &mesh, Vec3f p) {
  for (uint32_t c = 0; c < mesh.cellCount(); ++c)
    if (cellContains(mesh, c, p))
      return c;
  return kNoCell;
}

const Box3f kCube{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};

/// A ray from a random point well inside kCube in a random direction, and where it leaves the cube.
struct RayInCube {
  Vec3f origin;
  Ray ray;
  float tExit = 0.f;
};
RayInCube randomRayInCube(std::mt19937 &random) {
  std::uniform_real_distribution<float> u(-0.9f, 0.9f);
  RayInCube r;
  r.origin = {u(random), u(random), u(random)};
  r.ray = makeRay(r.origin, normalize(Vec3f{u(random), u(random), u(random)}));
  float tEnter;
  intersectBox(r.ray, kCube, 0.f, INFINITY, tEnter, r.tExit);
  return r;
}

} // namespace

// Samples a short step apart along random rays, each located from the previous one's cell with the weights
// carried along the ray, land in a cell holding them and get the value that cell interpolates there: with
// the tets' corners read, as on the GPU (whose policy reads them even where there are records), and with
// their affine records, as on the host.
TEST(WalkTets, CarriedWeightsGiveTheCellsOwnValues) {
  const Mesh mesh =
      buildMesh(makeBoxGrid(
                    CellType::Tetra, 5, kCube, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f, 11),
                "box");
  for (const auto [field, records, device] : {std::tuple{0, false, false},
                                              {-1, false, false},
                                              {0, true, false},
                                              {-1, true, false},
                                              {0, true, true},
                                              {-1, true, true}}) {
    SCOPED_TRACE(testing::Message() << "field " << field << (records ? ", affine records" : ", corners")
                                    << (device ? ", device sampling" : ", host sampling"));
    const bool cellData = field < 0;
    const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
    // Cell data: the cells' own index as their value, so that a value names its cell.
    std::vector<float> cellValues(mesh.tets.size() / 4);
    for (size_t c = 0; c < cellValues.size(); ++c)
      cellValues[c] = float(c);
    VolumeView volume;
    volume.mesh = makeMeshView(mesh, field);
    if (cellData) {
      volume.mesh.values = cellValues.data();
      volume.mesh.cellCentered = true;
    }
    volume.tetNeighbors = neighbors.data();
    const std::vector<TetAffine> affine = records ? buildTetAffine(volume.mesh) : std::vector<TetAffine>{};
    volume.tetAffine = records ? affine.data() : nullptr;
    std::mt19937 random(2);
    int carried = 0, walked = 0;
    for (int r = 0; r < 200; ++r) {
      const auto [origin, ray, tExit] = randomRayInCube(random);
      RayCell at;
      at.cell = cellHolding(volume.mesh, origin);
      ASSERT_NE(at.cell, kNoCell);
      for (float t = 0.f; t < tExit; t += 0.05f) {
        float value;
        const bool found = device ? walkTets<DeviceSampling>(volume, ray, t, at.cell, true, 64, at, value)
                                  : walkTets<HostSampling>(volume, ray, t, at.cell, true, 64, at, value);
        ASSERT_TRUE(found) << "ray " << r << " t " << t;
        const Vec3f p = ray.at(t);
        ASSERT_TRUE(cellContains(volume.mesh, at.cell, p));
        float expected;
        ASSERT_TRUE(sampleCell(volume.mesh, at.cell, p, expected));
        EXPECT_NEAR(value, expected, 1e-5f);
        (at.t < t ? carried : walked) += 1;
      }
    }
    // Most samples lie in the previous sample's tet here; the rest cross into a neighbour.
    EXPECT_GT(carried, walked);
    EXPECT_GT(walked, 200);
  }
}

// A guess at a sample's tet (the neighbouring ray's, see CellTrail) changes only where the walk starts: near
// or far, each sample is located in a tet holding it, with the value that tet interpolates there, as without
// a guess; and the weights carried on to the next sample are the ray's own.
TEST(WalkTets, GuessesChangeOnlyWhereTheWalkStarts) {
  const Mesh mesh =
      buildMesh(makeBoxGrid(
                    CellType::Tetra, 5, kCube, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f, 11),
                "box");
  const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
  for (const bool records : {false, true}) {
    SCOPED_TRACE(records ? "affine records" : "corners");
    VolumeView volume;
    volume.mesh = makeMeshView(mesh, 0);
    volume.tetNeighbors = neighbors.data();
    const std::vector<TetAffine> affine = records ? buildTetAffine(volume.mesh) : std::vector<TetAffine>{};
    volume.tetAffine = records ? affine.data() : nullptr;
    std::mt19937 random(5);
    std::uniform_int_distribution<uint32_t> anyTet(0, volume.mesh.tetCount - 1);
    int fromGuess = 0, samples = 0;
    for (int r = 0; r < 100; ++r) {
      const auto [origin, ray, tExit] = randomRayInCube(random);
      RayCell plain, guessed;
      plain.cell = guessed.cell = cellHolding(volume.mesh, origin);
      ASSERT_NE(plain.cell, kNoCell);
      for (float t = 0.f; t < tExit; t += 0.13f, ++samples) {
        const Vec3f p = ray.at(t);
        // The tet of a point a little off the ray, as a neighbouring ray's; or any tet at all.
        const uint32_t guess =
            samples % 2 ? cellHolding(volume.mesh, p + Vec3f{0.02f, -0.01f, 0.015f}) : anyTet(random);
        const uint32_t before = guessed.cell;
        float withoutGuess, withGuess;
        ASSERT_TRUE(
            locateSample<HostSampling>(volume, true, false, ray, t, 64, false, kNoCell, plain, withoutGuess));
        ASSERT_TRUE(
            locateSample<HostSampling>(volume, true, false, ray, t, 64, false, guess, guessed, withGuess))
            << "ray " << r << " t " << t;
        ASSERT_TRUE(cellContains(volume.mesh, guessed.cell, p));
        float expected;
        ASSERT_TRUE(sampleCell(volume.mesh, guessed.cell, p, expected));
        EXPECT_NEAR(withGuess, expected, 1e-5f);
        EXPECT_NEAR(withGuess, withoutGuess, 1e-5f);
        fromGuess += guessed.cell != before && guessed.cell == guess;
      }
    }
    // The walk from a guess is exercised: many samples that left the previous sample's tet lie in the guess.
    EXPECT_GT(fromGuess, samples / 10);
  }
}

// The face a ray leaves a tet by, named from the weights of a point beyond the tet, is the face whose
// triangle the ray crosses, found by intersecting the ray with each face; and where that face's neighbour is
// the boundary, a walk along the ray goes on across it rather than across the face the point lies furthest
// beyond.
TEST(WalkTets, LeaveByTheFaceTheRayCrosses) {
  std::mt19937 random(4);
  std::uniform_real_distribution<float> u(-1.f, 1.f), inside(0.05f, 1.f);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3f v[4];
    for (Vec3f &corner : v)
      corner = {u(random), u(random), u(random)};
    const float volume = dot(cross(v[1] - v[0], v[2] - v[0]), v[3] - v[0]);
    if (std::abs(volume) < 0.05f)
      continue;
    // A point inside, a direction, and a sample well past the tet.
    float b[4] = {inside(random), inside(random), inside(random), inside(random)};
    const float sum = b[0] + b[1] + b[2] + b[3];
    const Vec3f origin = (v[0] * b[0] + v[1] * b[1] + v[2] * b[2] + v[3] * b[3]) / sum;
    const Ray ray = makeRay(origin, normalize(Vec3f{u(random), u(random), u(random)}));
    float w[4], dw[4];
    ASSERT_TRUE(tetBarycentricsAlong(v[0], v[1], v[2], v[3], ray.at(5.f), ray.direction, w, dw));
    // The face opposite corner f has corners f + 1, f + 2, f + 3 (mod 4); the ray, starting inside, crosses
    // exactly one face's triangle at t > 0.
    int crossed = -1;
    for (int f = 0; f < 4; ++f) {
      const Vec3f a = v[(f + 1) & 3], e1 = v[(f + 2) & 3] - a, e2 = v[(f + 3) & 3] - a;
      const Vec3f q = cross(ray.direction, e2);
      const float det = dot(e1, q), inv = 1.f / det;
      const Vec3f s = ray.origin - a;
      const float alpha = dot(s, q) * inv;
      const Vec3f r = cross(s, e1);
      const float beta = dot(ray.direction, r) * inv, t = dot(e2, r) * inv;
      if (alpha > 1e-3f && beta > 1e-3f && alpha + beta < 1.f - 1e-3f && t > 0.f)
        crossed = f;
    }
    if (crossed < 0)
      continue; // through an edge or a corner, within the tolerance
    float lowest;
    const int beyond = smallestWeight(w, lowest);
    EXPECT_EQ(rayExitFace(w, dw, beyond), crossed) << "trial " << trial;
    uint32_t across[4] = {10, 11, 12, 13};
    across[beyond] = kNoCell;
    const uint32_t expected = crossed == beyond ? kNoCell : 10 + uint32_t(crossed);
    EXPECT_EQ(nextTet(Index4::load(across), beyond, w, dw, true), expected) << "trial " << trial;
    EXPECT_EQ(nextTet(Index4::load(across), beyond, w, dw, false), kNoCell);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

// Across every face inside a lattice of each cell type there is the cell on the other side, and only there:
// the relation is symmetric and the faces without one are the lattice's outer faces.
TEST(CellNeighbors, LinkEachInnerFaceBothWays) {
  constexpr int n = 4;
  const Box3f box{{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}};
  for (const CellType type : {CellType::Hexahedron, CellType::Wedge, CellType::Pyramid}) {
    SCOPED_TRACE(int(type));
    const Mesh mesh = buildMesh(makeBoxGrid(
                                    type, n, box, [](Vec3f p) { return p.x; }, 0.3f, 4),
                                "lattice");
    const MeshView view = makeMeshView(mesh, 0);
    const std::vector<uint32_t> neighbors = buildCellNeighbors(mesh);
    ASSERT_EQ(neighbors.size(), kMaxCellFaces * view.cellCount());
    uint64_t outer = 0;
    for (uint64_t cell = 0; cell < view.cellCount(); ++cell) {
      const int faces = cellFaces(cellType(view, cell)).count;
      for (int f = 0; f < kMaxCellFaces; ++f) {
        const uint32_t across = neighbors[kMaxCellFaces * cell + uint64_t(f)];
        if (f >= faces || across == kNoCell) {
          outer += f < faces;
          continue;
        }
        ASSERT_NE(across, cell);
        const uint32_t *back = neighbors.data() + kMaxCellFaces * uint64_t(across);
        EXPECT_EQ(std::count(back, back + kMaxCellFaces, uint32_t(cell)), 1);
      }
    }
    // The lattice's outer faces: a quad per cube side, but for wedges two triangles on the sides their
    // cut runs across.
    EXPECT_EQ(outer, uint64_t((type == CellType::Wedge ? 8 : 6) * n * n));
  }
}

/// A jittered lattice of cells of one type, with what walks across its cells need.
struct WalkableLattice {
  Mesh mesh;
  std::vector<uint32_t> neighbors;
  std::vector<Vec4f> planes;
  VolumeView volume;

  WalkableLattice(CellType type, int n, float (*field)(Vec3f), uint32_t seed)
      : mesh(buildMesh(makeBoxGrid(type, n, kCube, field, 0.3f, seed), "lattice")),
        neighbors(buildCellNeighbors(mesh)) {
    volume.mesh = makeMeshView(mesh, 0);
    planes = buildCellFacePlanes(volume.mesh);
    volume.cellNeighbors = neighbors.data();
    volume.cellFacePlanes = planes.data();
  }
};

// Samples along random rays through jittered lattices of each cell type, each walked to from the previous
// one's cell across faces, land in a cell holding them with the value that cell interpolates there. The
// faces' planes only approximate the faces of such distorted cells, so a walk may circle and give up (the
// caller then asks the seed grid or the BVH), but seldom.
TEST(WalkCells, FindTheCellHoldingEachSample) {
  for (const CellType type : {CellType::Hexahedron, CellType::Wedge, CellType::Pyramid}) {
    SCOPED_TRACE(int(type));
    const WalkableLattice lattice(
        type, 5, [](Vec3f p) { return p.x * p.y + p.z; }, 11);
    const VolumeView &volume = lattice.volume;
    // Hexahedra are left by their parametric coordinates: they need no planes.
    EXPECT_EQ(lattice.planes.empty(), type == CellType::Hexahedron);
    std::mt19937 random(3);
    int steps = 0, walks = 0, failed = 0;
    for (int r = 0; r < 100; ++r) {
      const auto [origin, ray, tExit] = randomRayInCube(random);
      RayCell at;
      at.cell = cellHolding(volume.mesh, origin);
      ASSERT_NE(at.cell, kNoCell);
      for (float t = 0.f; t < tExit - 1e-3f; t += 0.1f) {
        const uint32_t from = at.cell;
        const Vec3f p = ray.at(t);
        float value;
        ++walks;
        if (!walkCells<HostSampling>(volume, ray, t, at.cell, false, 64, at, value)) {
          ++failed;
          at.enter(cellHolding(volume.mesh, p));
          continue;
        }
        ASSERT_TRUE(cellContains(volume.mesh, at.cell, p));
        float expected;
        ASSERT_TRUE(sampleCell(volume.mesh, at.cell, p, expected));
        EXPECT_NEAR(value, expected, 1e-5f);
        steps += at.cell != from;
      }
    }
    EXPECT_GT(steps, 200); // the walks did cross cells
    EXPECT_LT(failed, walks / 100) << failed << " of " << walks;
  }
}

// Where a walk found a sample in another cell than a tet, the parametric coordinates it leaves are the
// sample's: per-point vectors interpolated at them (interpolatePointVectors, as shading does), rather than
// solved for again, reproduce a linear field, the points' own positions, as a solve does.
TEST(WalkCells, LeaveTheSamplesCoordinatesForVectors) {
  for (const CellType type : {CellType::Hexahedron, CellType::Wedge, CellType::Pyramid}) {
    SCOPED_TRACE(int(type));
    const WalkableLattice lattice(
        type, 4, [](Vec3f p) { return p.x + p.y; }, 7);
    const VolumeView &volume = lattice.volume;
    std::mt19937 random(5);
    int samples = 0;
    for (int r = 0; r < 40; ++r) {
      const auto [origin, ray, tExit] = randomRayInCube(random);
      RayCell at;
      at.cell = cellHolding(volume.mesh, origin);
      ASSERT_NE(at.cell, kNoCell);
      for (float t = 0.f; t < tExit - 1e-3f; t += 0.1f) {
        const Vec3f p = ray.at(t);
        float value;
        if (!walkCells<HostSampling>(volume, ray, t, at.cell, false, 64, at, value)) {
          at.enter(cellHolding(volume.mesh, p));
          continue;
        }
        ASSERT_TRUE(at.parametric);
        samples += at.t == t;
        RayCell unsolved = at; // the same cell, its coordinates to be solved for again
        unsolved.parametric = false;
        const Vec3f walked = interpolatePointVectors(volume.mesh, volume.mesh.points, at, p, t);
        const Vec3f solved = interpolatePointVectors(volume.mesh, volume.mesh.points, unsolved, p, t);
        EXPECT_LT(length(walked - p), 1e-4f);
        EXPECT_LT(length(walked - solved), 1e-4f);
      }
    }
    EXPECT_GT(samples, 100);
  }
}

// In a lattice of pyramids (six around each cube's centre) whose pyramids on the cube's sides are each cut
// into two tets, walks along random rays go from tets into pyramids across the triangles they share: linked
// both ways (linkTetsToOtherCells), a walk that starts in a tet goes on into the other cells rather than stop
// there as at the boundary, where the sampler would fall back on the BVH.
TEST(WalkCells, GoOnFromTetsIntoTheOtherCells) {
  UnstructuredGrid grid = makePyramidsAndTets(
      4, kCube, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f, 5);
  grid.fields.resize(1); // the point field
  const Mesh mesh = buildMesh(std::move(grid), "pyramids and tets");
  VolumeView volume;
  volume.mesh = makeMeshView(mesh, 0);
  ASSERT_GT(volume.mesh.tetCount, 0u);
  ASSERT_GT(volume.mesh.pyramidCount, 0u);
  const std::vector<uint32_t> cellNeighbors = buildCellNeighbors(mesh);
  const std::vector<Vec4f> planes = buildCellFacePlanes(volume.mesh);
  const std::vector<uint32_t> tetsOnly = buildTetNeighbors(mesh);
  std::vector<uint32_t> linked = tetsOnly;
  linkTetsToOtherCells(volume.mesh, cellNeighbors, linked);
  // Each new link names a pyramid holding the three corners of the tet's face.
  int links = 0;
  for (uint64_t entry = 0; entry < linked.size(); ++entry) {
    if (linked[entry] == tetsOnly[entry])
      continue;
    ++links;
    ASSERT_EQ(tetsOnly[entry], kNoCell);
    ASSERT_GE(linked[entry], volume.mesh.tetCount);
    int count;
    const uint32_t *corners = cellCorners(volume.mesh, linked[entry], count);
    const uint32_t *tet = volume.mesh.tets + 4 * (entry / 4);
    for (uint64_t i = 0; i < 4; ++i)
      if (i != entry % 4)
        EXPECT_EQ(std::count(corners, corners + count, tet[i]), 1);
  }
  EXPECT_GT(links, int(volume.mesh.tetCount));
  volume.cellNeighbors = cellNeighbors.data();
  volume.cellFacePlanes = planes.data();
  // Walks from each sample's cell to the next; those that start in a tet and end in another cell, and those
  // that fail.
  const auto walk = [&](const std::vector<uint32_t> &tetNeighbors, int &fromTets) {
    volume.tetNeighbors = tetNeighbors.data();
    std::mt19937 random(9);
    int failed = 0;
    fromTets = 0;
    for (int r = 0; r < 1000; ++r) {
      const auto [origin, ray, tExit] = randomRayInCube(random);
      RayCell at;
      at.enter(cellHolding(volume.mesh, origin));
      EXPECT_NE(at.cell, kNoCell);
      for (float t = 0.f; t < tExit - 1e-3f; t += 0.1f) {
        const uint32_t from = at.cell;
        const Vec3f p = ray.at(t);
        float value;
        if (!walkCells<HostSampling>(volume, ray, t, at.cell, true, 64, at, value)) {
          ++failed;
          at.enter(cellHolding(volume.mesh, p));
          continue;
        }
        EXPECT_TRUE(cellContains(volume.mesh, at.cell, p));
        fromTets += from < volume.mesh.tetCount && at.cell >= volume.mesh.tetCount;
      }
    }
    return failed;
  };
  int fromTets = 0, fromTetsUnlinked = 0;
  const int failed = walk(linked, fromTets);
  const int failedUnlinked = walk(tetsOnly, fromTetsUnlinked);
  EXPECT_GT(fromTets, 50);
  EXPECT_LT(failed, fromTets / 2) << failed << " walks failed";
  // Unlinked, such a walk stops at the tet's face as at the boundary.
  EXPECT_EQ(fromTetsUnlinked, 0);
  EXPECT_GE(failedUnlinked, failed + fromTets / 2) << failedUnlinked << " walks failed unlinked";
}
