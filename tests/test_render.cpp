// Whole-frame properties of the integrator: analytic transmittance, equivalence of the modes, no cracks at
// partition boundaries, independence of cell winding.
#include "api/access.h"
#include "engine/renderer.h"
#include "mesh/cell_neighbors.h"
#include "mesh/mesh_stats.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_neighbors.h"
#include "render/boundary_crossings.h"
#include "render/pixel.h"
#include <uvr/error.h>
#include <uvr/renderer.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

using namespace uvr;

namespace {

const Box3f kBox{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};

/// Uniform white with opacity `alpha` per unit distance for every value in [0, 1].
ColorMap constantMap(float alpha) {
  ColorMap map;
  map.rgbPoints = {0.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f};
  map.opacityPoints = {0.f, alpha, 0.5f, 0.f, 1.f, alpha, 0.5f, 0.f};
  return map;
}

/// Opacity rising over [0.55, 0.7] and colour varying throughout: some partitions transparent, some not.
ColorMap rampMap() {
  ColorMap map;
  map.rgbPoints = {0.f, 0.f, 0.f, 1.f, 0.5f, 0.f, 1.f, 0.f, 1.f, 1.f, 0.f, 0.f};
  map.opacityPoints = {0.f,  0.f,  0.5f, 0.f, 0.55f, 0.f,  0.5f, 0.f,
                       0.7f, 0.8f, 0.5f, 0.f, 1.f,   0.9f, 0.5f, 0.f};
  return map;
}

float radial(Vec3f p) { return 1.f - 0.5f * length(p); }

/// Keeps the tets of `mesh` whose centroid `keep` takes.
template <typename Keep> void keepTets(Mesh &mesh, Keep &&keep) {
  UninitVector<uint32_t> kept;
  for (size_t c = 0; c < mesh.tets.size(); c += 4) {
    Vec3f centroid{0.f, 0.f, 0.f};
    for (int i = 0; i < 4; ++i)
      centroid = centroid + mesh.points[mesh.tets[c + size_t(i)]] * 0.25f;
    if (keep(centroid))
      kept.insert(kept.end(), mesh.tets.begin() + long(c), mesh.tets.begin() + long(c) + 4);
  }
  mesh.tets = std::move(kept);
}

/// Whether a cell centre lies in the notched shell: a boundary with concave parts and a cavity.
bool inNotchedShell(Vec3f centre) {
  const float r = length(centre);
  return r > 0.45f && r < 0.95f && !(centre.x > 0.2f && centre.y > 0.2f);
}

/// A jittered lattice of tets cut to a shell with a notch: a boundary with concave parts and a cavity.
Mesh notchedShell() {
  Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 14, kBox, radial, 0.25f), "shell");
  keepTets(mesh, inNotchedShell);
  return mesh;
}

/// The notched shell in hexahedra, their faces bent by the jitter.
Mesh notchedHexShell() {
  return buildMesh(keepCells(makeBoxGrid(CellType::Hexahedron, 14, kBox, radial, 0.25f), inNotchedShell),
                   "hex shell");
}

/// Tets, pyramids and the faces between them (makePyramidsAndTets), with the point field alone.
Mesh pyramidsAndTets() {
  UnstructuredGrid grid = makePyramidsAndTets(6, kBox, radial, 0.2f);
  grid.fields.resize(1);
  return buildMesh(std::move(grid), "pyramids and tets");
}

Camera obliqueCamera() {
  Camera camera;
  camera.eye = {2.2f, 1.7f, 3.1f};
  camera.at = {0.05f, -0.03f, 0.02f};
  camera.fovy = 40.f;
  return camera;
}

/// The backends this machine can run: the CPU always, CUDA where it was built and a GPU is present.
std::vector<Backend> availableBackends() {
  std::vector<Backend> backends{Backend::Cpu};
  try {
    const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 1, kBox, [](Vec3f) { return 0.f; }), "probe");
    Renderer renderer(mesh, 0);
    renderer.setTransferFunction(TransferFunction(constantMap(0.5f), 0.f, 1.f));
    renderer.prepare(parseBackend("cuda"));
    backends.push_back(Backend::Cuda);
  } catch (const Error &) {
  }
  return backends;
}

// The backend the current test renders with.
Backend gBackend = Backend::Cpu;

RenderSettings settingsFor(RenderMode mode, float s1, float s2 = 0.f) {
  RenderSettings settings;
  settings.backend = gBackend;
  settings.width = settings.height = 64;
  settings.integrator.mode = mode;
  settings.integrator.s1 = s1;
  settings.integrator.s2 = s2 > 0.f ? s2 : s1;
  settings.integrator.unit = 0.1f;
  return settings;
}

/// Largest difference in accumulated opacity and in any 8-bit channel.
void expectSameFrame(const Frame &a, const Frame &b, float opacityTolerance, int byteTolerance) {
  ASSERT_EQ(a.opacity.size(), b.opacity.size());
  float worstOpacity = 0.f;
  for (size_t i = 0; i < a.opacity.size(); ++i)
    worstOpacity = std::max(worstOpacity, std::fabs(a.opacity[i] - b.opacity[i]));
  int worstByte = 0;
  for (size_t i = 0; i < a.image.rgb.size(); ++i)
    worstByte = std::max(worstByte, std::abs(int(a.image.rgb[i]) - int(b.image.rgb[i])));
  EXPECT_LE(worstOpacity, opacityTolerance);
  EXPECT_LE(worstByte, byteTolerance);
}

/// Renders `settings` (never terminating early) with a transfer function of constant opacity `alphaPerUnit`
/// over kBox, and checks each pixel's transmittance against exp(-kappa * length): samples stand for steps, so
/// it may be off by one sample of length `step`, plus `slack`. Returns how many pixels' rays meet the box.
int expectExponentialTransmittance(Renderer &renderer, RenderSettings settings, float alphaPerUnit,
                                   float step, float slack) {
  settings.integrator.terminationOpacity = 2.f;
  const Camera camera = obliqueCamera();
  const Frame frame = renderer.render(camera, settings);
  const CameraView view = makeCameraView(camera, settings.width, settings.height);
  const float kappa = -std::log(1.f - alphaPerUnit) / settings.integrator.unit;
  int inside = 0;
  for (int y = 0; y < settings.height; ++y)
    for (int x = 0; x < settings.width; ++x) {
      const Ray ray = view.ray(x, y);
      float t0, t1;
      const float length = intersectBox(ray, kBox, 0.f, INFINITY, t0, t1) ? t1 - t0 : 0.f;
      const float transmittance = 1.f - frame.opacity[size_t(y * settings.width + x)];
      const float tolerance = std::exp(-kappa * std::max(length - step, 0.f)) - std::exp(-kappa * length);
      EXPECT_NEAR(transmittance, std::exp(-kappa * length), tolerance + slack) << "pixel " << x << "," << y;
      inside += length > 0.f;
    }
  return inside;
}

class Integrator : public testing::TestWithParam<Backend> {
protected:
  void SetUp() override { gBackend = GetParam(); }
};

} // namespace

// Every integrator test runs on each backend the machine has, so CUDA is held to the same analytic results.
INSTANTIATE_TEST_SUITE_P(Backends, Integrator, testing::ValuesIn(availableBackends()),
                         [](const testing::TestParamInfo<Backend> &info) {
                           return std::string(backendName(info.param));
                         });

TEST_P(Integrator, ConstantFieldGivesExponentialTransmittance) {
  const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 8, kBox, [](Vec3f) { return 0.5f; }), "box");
  Renderer renderer(mesh, mesh.findField("f"), 64);
  const float alphaPerUnit = 0.3f;
  renderer.setTransferFunction(TransferFunction(constantMap(alphaPerUnit), 0.f, 1.f));
  for (RenderMode mode : {RenderMode::Reference, RenderMode::Skip, RenderMode::Full}) {
    const int inside = expectExponentialTransmittance(renderer, settingsFor(mode, 0.01f, 0.04f), alphaPerUnit,
                                                      mode == RenderMode::Full ? 0.04f : 0.01f, 1e-5f);
    EXPECT_GT(inside, 64 * 64 / 4);
  }
}

// A ray ends at the termination opacity, and the light it would still let through takes the colour where it
// ended: through a box of one colour, a ray that would have gone on to let through less than 0.2 % gives the
// image of a ray that never ends, to the byte, rather than one 1 % darker, and is wholly opaque; a ray that
// does not reach the termination opacity is as it was; and none is off by more than the 1 % of light left.
TEST_P(Integrator, AnEndedRayGivesTheRestOfItsLightItsColour) {
  const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 8, kBox, [](Vec3f) { return 0.5f; }), "box");
  Renderer renderer(mesh, mesh.findField("f"), 64);
  ColorMap map = constantMap(0.5f);
  map.rgbPoints = {0.f, 1.f, 0.6f, 0.2f, 1.f, 1.f, 0.6f, 0.2f};
  renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
  for (RenderMode mode : {RenderMode::Reference, RenderMode::Skip, RenderMode::Full})
    for (bool preintegrate : {false, true}) {
      RenderSettings ending = settingsFor(mode, 0.01f, 0.04f);
      ending.integrator.preintegrate = preintegrate;
      RenderSettings endless = ending;
      endless.integrator.terminationOpacity = 2.f;
      const Frame ended = renderer.render(obliqueCamera(), ending);
      const Frame whole = renderer.render(obliqueCamera(), endless);
      const std::string name = std::string(modeName(mode)) + (preintegrate ? " preintegrated" : " point");
      int opaque = 0;
      for (size_t i = 0; i < ended.opacity.size(); ++i) {
        int worstByte = 0;
        for (size_t c = 3 * i; c < 3 * i + 3; ++c)
          worstByte = std::max(worstByte, std::abs(int(ended.image.rgb[c]) - int(whole.image.rgb[c])));
        EXPECT_LE(worstByte, 3) << name << " pixel " << i;
        if (whole.opacity[i] >= 0.998f) {
          EXPECT_EQ(ended.opacity[i], 1.f) << name << " pixel " << i;
          EXPECT_LE(worstByte, 1) << name << " pixel " << i;
          ++opaque;
        } else if (!(ended.opacity[i] >= kTerminationOpacity)) {
          EXPECT_FLOAT_EQ(ended.opacity[i], whole.opacity[i]) << name << " pixel " << i;
          EXPECT_EQ(worstByte, 0) << name << " pixel " << i;
        }
      }
      EXPECT_GT(opaque, 64 * 64 / 4) << name;
    }
}

// Opacity constant and colour varying along x: partitions get different adaptive steps, up to s2 = 8·s1.
// Each sample stands for the distance to the next one, across partition boundaries too, so transmittance
// stays the analytic one to within one step (a sample on the mesh surface may miss it and take its step
// with it); an overhang or a gap at each of the ray's many partition boundaries would add up past that.
TEST_P(Integrator, AdaptiveStepsKeepTheTransmittance) {
  const Mesh mesh = buildMesh(
      makeBoxGrid(CellType::Tetra, 8, kBox, [](Vec3f p) { return 0.5f + 0.5f * p.x * p.x * p.x; }), "box");
  Renderer renderer(mesh, mesh.findField("f"), 16);
  const float alphaPerUnit = 0.3f;
  ColorMap map = constantMap(alphaPerUnit);
  map.rgbPoints = {0.f, 1.f, 0.f, 0.f, 0.5f, 0.f, 1.f, 0.f, 1.f, 0.f, 0.f, 1.f};
  renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
  const float s1 = 0.01f, s2 = 0.08f;
  for (RenderMode mode : {RenderMode::Adaptive, RenderMode::Full})
    expectExponentialTransmittance(renderer, settingsFor(mode, s1, s2), alphaPerUnit, s2, 1e-4f);
}

// Steps much longer than a hole in the mesh (hexahedra: no boundary crossings tell the march where the gaps
// are): where a sample lands in the hole, the march goes on a spacing at a time to the step's next sample, so
// the cells just past the hole are not lost with it. Each pixel's transmittance stays within one long step of
// the fixed-step marcher's, and every long-step frame is as opaque overall as that one.
TEST_P(Integrator, LongStepsPastAHoleKeepTheCellsBehindIt) {
  const Mesh mesh = buildMesh( // a slot two cells wide
      keepCells(makeBoxGrid(CellType::Hexahedron, 16, kBox, radial),
                [](Vec3f centre) { return !(std::fabs(centre.x) < 0.1f && std::fabs(centre.y) < 0.6f); }),
      "slotted box");
  Renderer renderer(mesh, mesh.findField("f"), 32);
  // Opacity constant, colour varying near the centre only: the other partitions take the long step.
  const float alphaPerUnit = 0.3f;
  ColorMap map = constantMap(alphaPerUnit);
  map.rgbPoints = {0.f, 1.f, 1.f, 1.f, 0.9f, 1.f, 1.f, 1.f, 1.f, 1.f, 0.f, 0.f};
  renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
  const float s1 = 0.01f, s2 = 0.32f; // a long step spans the slot (0.25) and more
  RenderSettings fixed = settingsFor(RenderMode::Reference, s1);
  fixed.integrator.terminationOpacity = 2.f;
  const Frame reference = renderer.render(obliqueCamera(), fixed);
  const float kappa = -std::log(1.f - alphaPerUnit) / fixed.integrator.unit;
  for (RenderMode mode : {RenderMode::Adaptive, RenderMode::Full}) {
    RenderSettings settings = settingsFor(mode, s1, s2);
    settings.integrator.terminationOpacity = 2.f;
    const Frame frame = renderer.render(obliqueCamera(), settings);
    double sum = 0.0, referenceSum = 0.0;
    for (size_t i = 0; i < frame.opacity.size(); ++i) {
      const float a = 1.f - frame.opacity[i], b = 1.f - reference.opacity[i];
      // Off by at most a long step's worth of absorption either way (a sample standing for a step that
      // leaves the mesh, or the last grid points before the ray comes back in).
      EXPECT_LE(std::fabs(std::log(std::max(a, 1e-6f)) - std::log(std::max(b, 1e-6f))), kappa * s2 + 1e-3f)
          << modeName(mode) << " pixel " << i;
      sum += frame.opacity[i];
      referenceSum += reference.opacity[i];
    }
    EXPECT_NEAR(sum / referenceSum, 1.0, 0.01) << modeName(mode);
    EXPECT_LT(frame.samplesTotal, reference.samplesTotal / 4) << modeName(mode); // the steps are long
  }
}

// Adaptive steps are whole numbers of s1. Colour varies only near the centre, so that the other partitions
// all take s2; two values of s2 that round to the same number of fixed steps then render the same frame with
// the same samples, about a third of reference's, and one that rounds to two steps takes about half.
TEST_P(Integrator, AdaptiveStepsAreWholeFixedSteps) {
  const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 8, kBox, radial, 0.2f), "box");
  Renderer renderer(mesh, mesh.findField("f"), 32);
  ColorMap map = constantMap(0.3f);
  map.rgbPoints = {0.f, 1.f, 1.f, 1.f, 0.9f, 1.f, 1.f, 1.f, 1.f, 1.f, 0.f, 0.f};
  renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
  const float s1 = 0.01f;
  auto render = [&](RenderMode mode, float s2) {
    return renderer.render(obliqueCamera(), settingsFor(mode, s1, s2));
  };
  const Frame reference = render(RenderMode::Reference, s1);
  const Frame three = render(RenderMode::Adaptive, 2.6f * s1),
              alsoThree = render(RenderMode::Adaptive, 3.4f * s1),
              two = render(RenderMode::Adaptive, 2.4f * s1);
  EXPECT_EQ(three.image.rgb, alsoThree.image.rgb);
  EXPECT_EQ(three.samplesPerPixel, alsoThree.samplesPerPixel);
  EXPECT_NE(three.image.rgb, two.image.rgb);
  const double total = double(reference.samplesTotal);
  // A third and a half, plus a sample where each partition's march begins and the centre's finer steps.
  EXPECT_GT(double(three.samplesTotal) / total, 1.0 / 3.0);
  EXPECT_LT(double(three.samplesTotal) / total, 0.42);
  EXPECT_GT(double(two.samplesTotal) / total, 1.0 / 2.0);
  EXPECT_LT(double(two.samplesTotal) / total, 0.58);
}

TEST_P(Integrator, SkippingChangesNoContributingSample) {
  const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 12, kBox, radial, 0.25f), "box");
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.prepare(Backend::Cpu);
  renderer.setTransferFunction(TransferFunction(rampMap(), 0.f, 1.f));
  ASSERT_GT(renderer.metadata().transparentCount, 0u);
  ASSERT_LT(renderer.metadata().transparentCount, renderer.partitions().count());
  const float s1 = 0.013f;
  const Frame reference = renderer.render(obliqueCamera(), settingsFor(RenderMode::Reference, s1));
  const Frame skip = renderer.render(obliqueCamera(), settingsFor(RenderMode::Skip, s1));
  const Frame adaptive = renderer.render(obliqueCamera(), settingsFor(RenderMode::Adaptive, s1));
  const Frame full = renderer.render(obliqueCamera(), settingsFor(RenderMode::Full, s1));
  expectSameFrame(reference, skip, 1e-5f, 1);
  expectSameFrame(skip, adaptive, 1e-5f, 1);
  expectSameFrame(skip, full, 1e-5f, 1);
  EXPECT_LT(skip.samplesTotal, reference.samplesTotal);
  EXPECT_EQ(full.samplesTotal, skip.samplesTotal);

  // With s2 > s1 adaptive sampling takes fewer samples and stays close.
  const Frame coarse = renderer.render(obliqueCamera(), settingsFor(RenderMode::Full, s1, 4.f * s1));
  EXPECT_LT(coarse.samplesTotal, skip.samplesTotal);
  expectSameFrame(skip, coarse, 0.05f, 16);
}

// A frame's sample totals are the sum and maximum of its per-pixel counts, and a frame that keeps neither
// per-pixel buffer has the same image and totals.
TEST_P(Integrator, FrameKeepsWhatIsAskedAndAlwaysItsSampleTotals) {
  const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 12, kBox, radial, 0.25f), "box");
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(TransferFunction(rampMap(), 0.f, 1.f));
  RenderSettings settings = settingsFor(RenderMode::Full, 0.02f, 0.08f);
  const Frame kept = renderer.render(obliqueCamera(), settings);
  ASSERT_EQ(kept.samplesPerPixel.size(), size_t(settings.width * settings.height));
  ASSERT_EQ(kept.opacity.size(), kept.samplesPerPixel.size());
  uint64_t total = 0;
  uint32_t most = 0;
  for (uint32_t n : kept.samplesPerPixel) {
    total += n;
    most = std::max(most, n);
  }
  EXPECT_GT(total, 0u);
  EXPECT_EQ(kept.samplesTotal, total);
  EXPECT_EQ(kept.samplesMax, most);

  settings.keepOpacity = false;
  settings.keepSamplesPerPixel = false;
  const Frame lean = renderer.render(obliqueCamera(), settings);
  EXPECT_TRUE(lean.opacity.empty());
  EXPECT_TRUE(lean.samplesPerPixel.empty());
  EXPECT_EQ(lean.image.rgb, kept.image.rgb);
  EXPECT_EQ(lean.samplesTotal, total);
  EXPECT_EQ(lean.samplesMax, most);

  // The premultiplied colours alone, as floats and in 16 bits a channel: the same values, rounded, and over
  // a black background the image's own.
  settings.keepImage = false;
  settings.keepPremultipliedRgba = true;
  settings.keepPremultipliedRgba16 = true;
  const Frame colours = renderer.render(obliqueCamera(), settings);
  EXPECT_TRUE(colours.image.rgb.empty());
  ASSERT_EQ(colours.premultipliedRgba.size(), 4 * kept.opacity.size());
  ASSERT_EQ(colours.premultipliedRgba16.size(), colours.premultipliedRgba.size());
  int opaque = 0;
  for (size_t i = 0; i < colours.premultipliedRgba.size(); ++i) {
    const float value = colours.premultipliedRgba[i];
    EXPECT_EQ(colours.premultipliedRgba16[i], uint16_t(std::clamp(value, 0.f, 1.f) * 65535.f + 0.5f)) << i;
    if (i % 4 == 3) {
      EXPECT_FLOAT_EQ(value, kept.opacity[i / 4]) << i;
      opaque += value > 0.5f;
    } else {
      EXPECT_EQ(PixelTarget::toByte(value), kept.image.rgb[3 * (i / 4) + i % 4]) << i;
    }
  }
  EXPECT_GT(opaque, 0);
  EXPECT_EQ(colours.samplesTotal, total);
}

TEST_P(Integrator, NoCracksAtPartitionBoundaries) {
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(makeBoxGrid(type, 10, kBox, [](Vec3f) { return 0.5f; }), "box");
    Renderer one(mesh, mesh.findField("f"), 1u << 30);
    Renderer many(mesh, mesh.findField("f"), 8);
    one.prepare(Backend::Cpu);
    many.prepare(Backend::Cpu);
    ASSERT_EQ(one.partitions().count(), 1u);
    ASSERT_GT(many.partitions().count(), 100u);
    one.setTransferFunction(TransferFunction(constantMap(0.2f), 0.f, 1.f));
    many.setTransferFunction(TransferFunction(constantMap(0.2f), 0.f, 1.f));

    // Put the eye on the root's split plane, and on a second split plane below it, so that the middle column
    // and middle row of an odd-sized image run exactly along planes, through edges and corners of partitions.
    const KdNode &root = many.partitions().nodes[0];
    ASSERT_NE(root.axis, KdNode::kLeaf);
    const KdNode &below = many.partitions().nodes[root.child];
    const int first = int(root.axis);
    const bool secondSplit = below.axis != KdNode::kLeaf && below.axis != root.axis;
    const int second = secondSplit ? int(below.axis) : (first + 1) % 3;
    const int depth = 3 - first - second;
    Camera camera;
    camera.eye[first] = root.split;
    if (secondSplit)
      camera.eye[second] = below.split;
    camera.eye[depth] = 4.f;
    camera.at = camera.eye;
    camera.at[depth] = 0.f;
    camera.up = {0.f, 0.f, 0.f};
    camera.up[(depth + 1) % 3] = 1.f;
    for (RenderMode mode : {RenderMode::Skip, RenderMode::Full}) {
      RenderSettings settings = settingsFor(mode, 0.02f);
      settings.width = settings.height = 65;
      const Frame a = one.render(camera, settings);
      const Frame b = many.render(camera, settings);
      expectSameFrame(a, b, 1e-5f, 0);
    }
  }
}

// Leaf by leaf, or with some inner nodes taken whole, the intervals a ray visits tile it front to back with
// neither gaps nor overlaps, each the node's stretch of the ray: marching a node whole takes the samples its
// leaves would; and the last interval, past the partitions, where one is asked for, comes once and last.
TEST(Partitions, TraversalTilesTheRayLeafByLeafOrWithWholeNodes) {
  const Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 10, kBox, radial, 0.2f), "box");
  const Partitions parts = buildPartitions(makeMeshView(mesh, 0), 8);
  ASSERT_GT(parts.count(), 100u);
  const PartitionsView view = parts.view();
  const std::vector<std::pair<const char *, std::function<bool(uint32_t)>>> choices = {
      {"leaves", [](uint32_t) { return false; }},
      {"every third node", [](uint32_t node) { return node % 3 == 1; }},
      {"the root", [](uint32_t) { return true; }}};
  const Camera camera = obliqueCamera();
  const CameraView rays = makeCameraView(camera, 23, 17);
  for (const auto &[name, whole] : choices) {
    int wholeVisits = 0;
    for (int y = 0; y < 17; ++y)
      for (int x = 0; x < 23; ++x) {
        const Ray ray = rays.ray(x, y);
        float tMin, tMax;
        if (!intersectBox(ray, view.rootBounds, 0.f, INFINITY, tMin, tMax))
          continue;
        float reached = tMin;
        int ends = 0; // the last interval, past the partitions, asked for once and visited last
        traversePartitions(
            view, ray, tMin, tMax, nullptr, whole,
            [&](uint32_t node, float t0, float t1) {
              if (node == KdNode::kNone) {
                EXPECT_EQ(ends, 1) << name;
                EXPECT_EQ(t0, tMax + 1.f);
                reached = t1;
                return true;
              }
              const bool leaf = view.nodes[node].axis == KdNode::kLeaf;
              EXPECT_TRUE(leaf || whole(node)) << name << ": node " << node;
              wholeVisits += !leaf;
              EXPECT_EQ(t0, reached) << name << ": pixel " << x << "," << y << ", node " << node;
              EXPECT_LT(t0, t1);
              reached = t1;
              return true;
            },
            [&](float &t0, float &t1) {
              ++ends;
              t0 = t1 = tMax + 1.f;
              return ends == 1;
            });
        EXPECT_EQ(ends, 1) << name;
        EXPECT_EQ(reached, tMax + 1.f) << name << ": pixel " << x << "," << y;
      }
    if (std::string(name) != "leaves")
      EXPECT_GT(wholeVisits, 0) << name;
  }
}

TEST_P(Integrator, WindingDoesNotChangeTheImage) {
  const UnstructuredGrid grid = makeBoxGrid(CellType::Hexahedron, 6, kBox, radial, 0.2f);
  auto reversed = [&](bool every) {
    UnstructuredGrid copy = grid;
    for (size_t c = 0; c + 1 < copy.offsets.size(); ++c) {
      if (!every && c % 2)
        continue;
      int64_t *v = &copy.connectivity[size_t(copy.offsets[c])];
      for (int i = 0; i < 4; ++i)
        std::swap(v[i], v[i + 4]);
    }
    return copy;
  };
  const Mesh correct = buildMesh(UnstructuredGrid(grid), "correct");
  const Mesh inverted = buildMesh(reversed(true), "inverted");
  const Mesh mixed = buildMesh(reversed(false), "mixed");
  EXPECT_EQ(correct.invertedCells, 0u);
  EXPECT_EQ(inverted.invertedCells, correct.cellCount());
  EXPECT_EQ(mixed.invertedCells, (correct.cellCount() + 1) / 2);

  Frame frames[3];
  const Mesh *meshes[3] = {&correct, &inverted, &mixed};
  for (int i = 0; i < 3; ++i) {
    Renderer renderer(*meshes[i], meshes[i]->findField("f"), 16);
    renderer.setTransferFunction(TransferFunction(rampMap(), 0.f, 1.f));
    frames[i] = renderer.render(obliqueCamera(), settingsFor(RenderMode::Full, 0.02f, 0.08f));
  }
  EXPECT_GT(frames[0].samplesTotal, 0u);
  expectSameFrame(frames[0], frames[1], 0.f, 0);
  expectSameFrame(frames[0], frames[2], 0.f, 0);
}

namespace {

/// The skipping modes give `reference`'s image of the renderer's mesh under a constant translucent
/// function, from outside and from a point inside its cavity.
void expectSkippingGivesTheReferenceImage(Renderer &renderer) {
  renderer.setTransferFunction(TransferFunction(constantMap(0.3f), 0.f, 1.f));
  Camera inside;
  inside.eye = {0.02f, -0.03f, 0.01f};
  inside.at = {1.f, 0.4f, 0.2f};
  inside.fovy = 70.f;
  for (const Camera &camera : {obliqueCamera(), inside}) {
    const Frame reference = renderer.render(camera, settingsFor(RenderMode::Reference, 0.013f));
    ASSERT_GT(reference.samplesTotal, 0u);
    for (RenderMode mode : {RenderMode::Skip, RenderMode::Full})
      expectSameFrame(reference, renderer.render(camera, settingsFor(mode, 0.013f)), 1e-5f, 1);
  }
}

} // namespace

// Rays from outside the mesh march only between their first and last boundary crossings: on a mesh with
// concave parts and a cavity, every mode still gives `reference`'s image, from outside and from within the
// cavity (where no crossings apply), and a ray that crosses no boundary face takes no sample.
TEST_P(Integrator, BoundaryCrossingsLeaveTheImageAsItIs) {
  const Mesh mesh = notchedShell();
  Renderer renderer(mesh, mesh.findField("f"), 32);
  expectSkippingGivesTheReferenceImage(renderer);
  const RenderSettings settings = settingsFor(RenderMode::Skip, 0.013f);
  const CameraView view = makeCameraView(obliqueCamera(), settings.width, settings.height);
  renderer.prepare(Backend::Cpu);
  ASSERT_TRUE(crossingsApply(view, renderer.partitions().rootBounds));
  std::vector<uint64_t> start, keys;
  findBoundaryCrossings(makeMeshView(mesh, -1), listBoundaryFaces(buildTetNeighbors(mesh)), view, start,
                        keys);
  const Frame skip = renderer.render(obliqueCamera(), settings);
  int uncrossed = 0;
  for (size_t pixel = 0; pixel + 2 < start.size(); ++pixel)
    if (start[pixel] == start[pixel + 1]) {
      EXPECT_EQ(skip.samplesPerPixel[pixel], 0u) << "pixel " << pixel;
      ++uncrossed;
    }
  EXPECT_GT(uncrossed, 0);
}

// Two slabs with empty space between them, seen across both: the skipping modes take no sample in the gap,
// which the ray leaves the mesh into and enters it again from, and still give `reference`'s image.
TEST_P(Integrator, GapsBetweenBoundaryCrossingsTakeNoSample) {
  Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 10, kBox, radial), "slabs");
  // The gap is at least 0.6 wide: cells are 0.2 on a side.
  keepTets(mesh, [](Vec3f centroid) { return std::fabs(centroid.z) > 0.5f; });
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(TransferFunction(constantMap(0.05f), 0.f, 1.f));
  Camera along;
  along.eye = {0.13f, 0.07f, 5.f};
  along.at = {0.f, 0.f, 0.f};
  along.fovy = 12.f;
  const float s1 = 0.02f;
  auto settings = [&](RenderMode mode) {
    RenderSettings chosen = settingsFor(mode, s1);
    chosen.integrator.terminationOpacity = 2.f; // every ray goes through both slabs
    return chosen;
  };
  const Frame reference = renderer.render(along, settings(RenderMode::Reference));
  for (RenderMode mode : {RenderMode::Skip, RenderMode::Full}) {
    const Frame frame = renderer.render(along, settings(mode));
    expectSameFrame(reference, frame, 1e-5f, 1);
    // Rays through both slabs cross 2 - 0.6 of mesh at most, where `reference` takes a sample every s1 of
    // the box's 2.
    int across = 0;
    for (size_t pixel = 0; pixel < frame.samplesPerPixel.size(); ++pixel) {
      if (reference.samplesPerPixel[pixel] < uint32_t(1.9f / s1))
        continue;
      ++across;
      EXPECT_LE(frame.samplesPerPixel[pixel], uint32_t(1.4f / s1) + 2) << "pixel " << pixel;
    }
    EXPECT_GT(across, 1000);
  }
}

// The boundary faces of meshes with other cells than tets: the faces with no cell across, a tet's too where
// no pyramid lies across it. On a box their areas add up to the box's, each face counted once.
TEST(BoundaryCrossings, CellFacesCoverTheBoundaryOnce) {
  std::vector<Mesh> meshes;
  meshes.push_back(buildMesh(makeBoxGrid(CellType::Hexahedron, 5, kBox, radial, 0.2f), "hexes"));
  meshes.push_back(pyramidsAndTets());
  for (const Mesh &mesh : meshes) {
    const MeshView view = makeMeshView(mesh, -1);
    const std::vector<uint32_t> tetNeighbors = buildTetNeighbors(mesh);
    const std::vector<uint32_t> faces = listBoundaryCellFaces(
        view, tetNeighbors.empty() ? nullptr : tetNeighbors.data(), buildCellNeighbors(mesh));
    EXPECT_TRUE(std::is_sorted(faces.begin(), faces.end()));
    double area = 0.0;
    uint64_t tetFaces = 0;
    for (uint32_t face : faces) {
      Vec3f c[4], inner;
      const int count = boundaryFaceCorners(view, face, c, inner);
      area += 0.5 * double(length(cross(c[1] - c[0], c[2] - c[0])));
      if (count == 4)
        area += 0.5 * double(length(cross(c[2] - c[0], c[3] - c[0])));
      tetFaces += boundaryFaceCell(view, face) < view.tetCount;
    }
    EXPECT_NEAR(area, 24.0, 1e-3) << mesh.tetCount() << " tets";
    EXPECT_EQ(tetFaces > 0, mesh.tetCount() > 0);
  }
}

// Boundary crossings of other cells than tets: on the notched shell in hexahedra (their faces bent, each
// crossed as the bilinear patch it is) and on a box of pyramids and tets, the skipping modes give
// `reference`'s image, from outside and from within the cavity, and a ray that crosses no boundary face takes
// no sample.
TEST_P(Integrator, BoundaryCrossingsOfOtherCellsLeaveTheImageAsItIs) {
  std::vector<Mesh> meshes;
  meshes.push_back(notchedHexShell());
  meshes.push_back(pyramidsAndTets());
  for (const Mesh &mesh : meshes) {
    Renderer renderer(mesh, mesh.findField("f"), 32);
    expectSkippingGivesTheReferenceImage(renderer);
    const RenderSettings settings = settingsFor(RenderMode::Skip, 0.013f);
    const MeshView view = makeMeshView(mesh, -1);
    const std::vector<uint32_t> tetNeighbors = buildTetNeighbors(mesh);
    std::vector<uint64_t> start, keys;
    findBoundaryCrossings(view,
                          listBoundaryCellFaces(view, tetNeighbors.empty() ? nullptr : tetNeighbors.data(),
                                                buildCellNeighbors(mesh)),
                          makeCameraView(obliqueCamera(), settings.width, settings.height), start, keys);
    const Frame skip = renderer.render(obliqueCamera(), settings);
    int uncrossed = 0, crossed = 0;
    for (size_t pixel = 0; pixel + 2 < start.size(); ++pixel) {
      if (start[pixel] == start[pixel + 1]) {
        EXPECT_EQ(skip.samplesPerPixel[pixel], 0u) << "pixel " << pixel;
        ++uncrossed;
      }
      crossed += start[pixel] != start[pixel + 1];
    }
    EXPECT_GT(uncrossed, 0);
    EXPECT_GT(crossed, 1000);
  }
}

// On the notched hex shell seen from outside, with a function opaque in the shell's inner half, `skip`
// marches each ray only from where it enters the shell until it turns opaque: without the crossings it
// marched the empty space in the partitions' boxes (the corners of the box, the notch, around the shell).
TEST_P(Integrator, SkippingHexahedraMarchesFromTheBoundary) {
  const Mesh mesh = notchedHexShell();
  Renderer renderer(mesh, mesh.findField("f"), 32);
  renderer.setTransferFunction(TransferFunction(rampMap(), 0.f, 1.f));
  const Frame reference = renderer.render(obliqueCamera(), settingsFor(RenderMode::Reference, 0.013f));
  const Frame skip = renderer.render(obliqueCamera(), settingsFor(RenderMode::Skip, 0.013f));
  expectSameFrame(reference, skip, 1e-5f, 1);
  EXPECT_LT(2 * skip.samplesTotal, reference.samplesTotal);
}

// Along a ray that enters the mesh at t = 1, leaves at 3, enters again at 6 and leaves at 9, samples in the
// gap move on to its end, and each call says which face the ray came back in by since the one before.
TEST(BoundaryCrossings, AfterGapFollowsTheMarch) {
  const uint64_t keys[4] = {crossingKey(1.f, 10, false), crossingKey(3.f, 11, true),
                            crossingKey(6.f, 12, false), crossingKey(9.f, 13, true)};
  BoundaryCrossings crossings;
  crossings.keys = keys;
  crossings.count = 4;
  const float margin = 0.01f;
  struct Step {
    float t, resume;
    uint32_t entered;
  };
  // A sample at a crossing has passed it; one within the margin of the gap's ends is taken where it is.
  const Step steps[] = {
      {0.5f, 0.5f, kNoCell},     {1.f, 1.f, 10},          {2.f, 2.f, kNoCell},       {2.5f, 2.5f, kNoCell},
      {3.005f, 3.005f, kNoCell}, {4.f, 6.f - margin, 12}, {5.995f, 5.995f, kNoCell}, {7.f, 7.f, 12},
      {8.f, 8.f, kNoCell},       {10.f, 10.f, kNoCell}};
  CrossingCursor cursor;
  for (const Step &step : steps) {
    uint32_t entered;
    EXPECT_FLOAT_EQ(afterGap(crossings, step.t, margin, cursor, entered), step.resume) << "t " << step.t;
    EXPECT_EQ(entered, step.entered) << "t " << step.t;
  }
  // Samples spaced past a whole gap: the face the ray re-entered by, though no sample fell in the gap.
  CrossingCursor skipping;
  uint32_t entered;
  EXPECT_FLOAT_EQ(afterGap(crossings, 2.f, margin, skipping, entered), 2.f);
  EXPECT_EQ(entered, 10u);
  EXPECT_FLOAT_EQ(afterGap(crossings, 7.f, margin, skipping, entered), 7.f);
  EXPECT_EQ(entered, 12u);
}

// Each pixel's crossings with the boundary faces, against every face tested in double precision: the
// projected boxes leave out no pixel whose ray crosses a face, the crossings come in order of t, and each
// says rightly whether the ray leaves the mesh there.
TEST(BoundaryCrossings, FindEachRaysFirstAndLastCrossing) {
  const Mesh mesh = notchedShell();
  const MeshView view = makeMeshView(mesh, -1);
  const std::vector<uint32_t> faces = listBoundaryFaces(buildTetNeighbors(mesh));
  ASSERT_GT(faces.size(), 1000u);
  const CameraView camera =
      makeCameraView(obliqueCamera(), 53, 41); // odd and unequal: no symmetry hides a swap
  std::vector<uint64_t> start, keys;
  findBoundaryCrossings(view, faces, camera, start, keys);
  ASSERT_EQ(start.size(), 53u * 41u + 2u);
  ASSERT_EQ(start.back(), keys.size());
  using Vec3d = std::array<double, 3>;
  auto sub = [](Vec3d a, Vec3d b) { return Vec3d{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto dot3 = [](Vec3d a, Vec3d b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  auto cross3 = [](Vec3d a, Vec3d b) {
    return Vec3d{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto widen = [](Vec3f p) { return Vec3d{p.x, p.y, p.z}; };
  int crossed = 0, grazed = 0, edgeOnly = 0, inner = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Ray ray = camera.ray(x, y);
      const Vec3d o = widen(ray.origin), d = widen(ray.direction);
      const size_t pixel = size_t(y) * size_t(camera.width) + size_t(x);
      const BoundaryCrossings found = pixelCrossings(start.data(), keys.data(), pixel);
      ASSERT_TRUE(std::is_sorted(found.keys, found.keys + found.count)) << "pixel " << x << "," << y;
      double least = INFINITY, most = -INFINITY, firstFaceT = INFINITY;
      for (uint32_t face : faces) {
        Vec3f a, b, c;
        tetFaceCorners(view, face, a, b, c);
        const Vec3d e1 = sub(widen(b), widen(a)), e2 = sub(widen(c), widen(a)), tv = sub(o, widen(a));
        const Vec3d pv = cross3(d, e2), qv = cross3(tv, e1);
        const double det = dot3(e1, pv);
        const double u = dot3(tv, pv) / det, v = dot3(d, qv) / det, t = dot3(e2, qv) / det;
        if (!(det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0))
          continue;
        least = std::min(least, t), most = std::max(most, t);
        if (face == found.face)
          firstFaceT = t;
        if (!(u > 1e-3 && v > 1e-3 && u + v < 1.0 - 1e-3))
          continue;
        // A crossing well inside its face is listed, saying whether the ray leaves the mesh there: whether it
        // runs along the face's normal pointing away from the tet's fourth corner.
        ++inner;
        const Vec3d normal = cross3(e1, e2);
        const Vec3f fourth = view.points[view.tets[4 * size_t(face >> 2) + (face & 3u)]];
        const bool outward = dot3(normal, sub(widen(fourth), widen(a))) < 0.0;
        const bool exits = (dot3(d, normal) > 0.0) == outward;
        const uint64_t *listed = std::find_if(found.keys, found.keys + found.count,
                                              [&](uint64_t key) { return crossingFace(key) == face; });
        ASSERT_NE(listed, found.keys + found.count) << "pixel " << x << "," << y << ", face " << face;
        EXPECT_EQ(crossingExits(*listed), exits) << "pixel " << x << "," << y << ", face " << face;
      }
      if (least == INFINITY) {
        edgeOnly += found.first != INFINITY; // within the edge tolerance of a face, and no more
        continue;
      }
      // Never later than the first exact crossing, nor earlier than the last: a ray grazing a face within
      // the edge tolerance may cross it before or after every exact crossing.
      ++crossed;
      ASSERT_NE(found.first, INFINITY) << "pixel " << x << "," << y;
      EXPECT_LE(found.first, least + 1e-4 * least) << "pixel " << x << "," << y;
      EXPECT_GE(found.last, most - 1e-4 * most) << "pixel " << x << "," << y;
      grazed += found.first < least - 1e-3 || found.last > most + 1e-3;
      if (firstFaceT != INFINITY) // unless only its edge tolerance took it
        EXPECT_NEAR(found.first, firstFaceT, 1e-5 * firstFaceT) << "pixel " << x << "," << y;
    }
  EXPECT_GT(crossed, 500);
  EXPECT_GT(inner, 2 * crossed); // the shell's cavity: most rays cross four times
  EXPECT_LT(crossed, 53 * 41 - 200) << "too few rays miss the mesh to test";
  EXPECT_LE(grazed + edgeOnly, crossed / 50) << grazed << " grazing, " << edgeOnly << " at an edge alone";
}

TEST(TransferFunction, MetadataMatchesAScanOfTheTable) {
  const TransferFunction tf(rampMap(), 0.f, 1.f, 257);
  const std::vector<Vec4f> &table = tf.table();
  for (float a : {0.f, 0.1f, 0.5f, 0.61f, 0.99f})
    for (float b : {0.f, 0.2f, 0.55f, 0.7f, 1.f, 3.f}) {
      if (b < a)
        continue;
      const int first = int(std::floor(a * 256.f)), last = std::min(256, int(std::ceil(b * 256.f)));
      float maxOpacity = 0.f;
      double sum[4] = {}, squares[4] = {};
      for (int i = first; i <= last; ++i) {
        maxOpacity = std::max(maxOpacity, table[size_t(i)].w);
        const double c[4] = {table[size_t(i)].x, table[size_t(i)].y, table[size_t(i)].z, table[size_t(i)].w};
        for (int k = 0; k < 4; ++k)
          sum[k] += c[k], squares[k] += c[k] * c[k];
      }
      double variance = 0.0;
      const double n = last - first + 1;
      for (int k = 0; k < 4; ++k)
        variance += std::max(0.0, squares[k] / n - (sum[k] / n) * (sum[k] / n));
      EXPECT_EQ(tf.maxOpacity(a, b), maxOpacity) << a << ".." << b;
      EXPECT_NEAR(tf.colorVariance(a, b), variance, 1e-6) << a << ".." << b;
    }
  EXPECT_EQ(tf.maxOpacity(0.f, 0.5f), 0.f);
  EXPECT_GT(tf.maxOpacity(0.f, 0.6f), 0.f);
}

// ParaView's reset camera: the bounding sphere touches the narrower of the two view angles and fits the
// other.
// Above finestStepSigma the paper's step rounds to one fixed step, below it to more: the integrator may march
// partitions above it at s1 without computing their steps, and subtrees of them whole.
TEST(TransferFunction, FinestStepSigmaIsWhereStepsRoundToOneFixedStep) {
  for (const auto &[s1, s2, p] :
       {std::array<float, 3>{0.01f, 0.08f, 4.f}, {0.5f, 0.9f, 1.f}, {1.f, 3.f, 2.f}, {0.02f, 0.05f, 7.5f}}) {
    const float threshold = finestStepSigma(s1, s2, p);
    ASSERT_GT(threshold, 0.f);
    ASSERT_LT(threshold, 1.f);
    for (float sigma = 0.f; sigma <= 1.f; sigma += 1.f / 512.f) {
      if (std::fabs(sigma - threshold) < 1e-4f)
        continue;
      const float steps = std::rint(adaptiveStepSize(s1, s2, p, sigma) / s1);
      EXPECT_EQ(steps <= 1.f, sigma > threshold) << "s2 " << s2 << ", p " << p << ", sigma " << sigma;
    }
  }
  EXPECT_EQ(finestStepSigma(0.1f, 0.1f, 2.f), -INFINITY);
}

TEST(Camera, ResetCameraFitsTheBoundingSphereInBothAngles) {
  const Box3f box{{-1.f, -2.f, 0.f}, {3.f, 1.f, 5.f}};
  const float radius = 0.5f * length(box.size());
  for (const auto [width, height] : {std::pair{400, 400}, std::pair{800, 400}, std::pair{300, 600}}) {
    const Camera camera = frameBounds(box, 30.f, float(width) / float(height));
    const CameraView view = makeCameraView(camera, width, height);
    const float sphereHalfAngle = std::asin(radius / length(camera.eye - box.center()));
    const float verticalHalfAngle = std::atan(length(view.up));
    const float horizontalHalfAngle = std::atan(length(view.right));
    EXPECT_NEAR(verticalHalfAngle, 15.f * float(M_PI) / 180.f, 1e-5f);
    EXPECT_NEAR(sphereHalfAngle, std::min(verticalHalfAngle, horizontalHalfAngle), 1e-5f)
        << width << "x" << height;
  }
}

// The pixels a box can cover (what a rank's image is scanned for colour in): every pixel whose ray meets the
// box lies among them, and, seen whole from in front, they reach only a few pixels past those; a box
// reaching behind the eye gives the whole image.
TEST(Camera, BoxPixelsHoldEveryRayThatMeetsTheBox) {
  std::mt19937 random(3);
  std::uniform_real_distribution<float> unit(-1.f, 1.f);
  const int width = 120, height = 80;
  int partly = 0, behind = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Camera camera;
    camera.eye = Vec3f{unit(random), unit(random), unit(random)} * (trial % 3 == 0 ? 2.f : 6.f);
    camera.at = Vec3f{unit(random), unit(random), unit(random)};
    camera.fovy = 20.f + 40.f * (unit(random) + 1.f);
    const Vec3f corner{unit(random) * 2.f, unit(random) * 2.f, unit(random) * 2.f};
    const Box3f box{corner,
                    corner + Vec3f{1.f + unit(random), 1.f + unit(random), 1.f + unit(random)} * 0.8f};
    const PixelBox pixels = boxPixels(camera, width, height, box);
    const CameraView view = makeCameraView(camera, width, height);
    PixelBox hit{width, 0, height, 0};
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        float t0, t1;
        if (!intersectBox(view.ray(x, y), box, 0.f, INFINITY, t0, t1))
          continue;
        EXPECT_TRUE(x >= pixels.x0 && x < pixels.x1 && y >= pixels.y0 && y < pixels.y1)
            << "trial " << trial << ": pixel " << x << "," << y;
        hit = {std::min(hit.x0, x), std::max(hit.x1, x + 1), std::min(hit.y0, y), std::max(hit.y1, y + 1)};
      }
    bool inFront = true;
    for (int c = 0; c < 8; ++c) {
      const Vec3f p{c & 1 ? box.upper.x : box.lower.x, c & 2 ? box.upper.y : box.lower.y,
                    c & 4 ? box.upper.z : box.lower.z};
      inFront = inFront && dot(p - view.eye, view.forward) > 0.f;
    }
    if (!inFront) {
      ++behind;
      EXPECT_TRUE(pixels.x0 == 0 && pixels.x1 == width && pixels.y0 == 0 && pixels.y1 == height);
    } else if (hit.x0 > 0 && hit.x0 < hit.x1 && hit.x1 < width && hit.y0 > 0 && hit.y1 < height) {
      // Seen whole: a few pixels more than those hit (a corner's projection may lie between pixel centres).
      ++partly;
      EXPECT_LE(hit.x0 - pixels.x0, 6);
      EXPECT_LE(pixels.x1 - hit.x1, 6);
      EXPECT_LE(hit.y0 - pixels.y0, 6);
      EXPECT_LE(pixels.y1 - hit.y1, 6);
    }
  }
  EXPECT_GT(partly, 5);
  EXPECT_GT(behind, 0);
}

// Partitions of the default size unless a leaf size is given, and the CPU's count follows it.
TEST(Renderer, LeafSizeIsTheDefaultUnlessGiven) {
  EXPECT_EQ(defaultLeafSize(1000), kSmallestDefaultLeafSize);
  EXPECT_EQ(defaultLeafSize(300'000'000), 300'000'000 / kDefaultPartitions);
  EXPECT_EQ(defaultLeafSize(uint64_t(1) << 50), UINT32_MAX);
  const Mesh mesh = buildMesh(
      makeBoxGrid(CellType::Tetra, 8, {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}}, [](Vec3f p) { return p.x; }),
      "box");
  Renderer byDefault(mesh, mesh.findField("f"));
  EXPECT_EQ(byDefault.leafSize(), defaultLeafSize(mesh.cellCount()));
  Renderer given(mesh, mesh.findField("f"), 7);
  EXPECT_EQ(given.leafSize(), 7u);
  EXPECT_THROW(given.partitionCount(Backend::Cpu), Error); // nothing is built on a read
  byDefault.prepare(Backend::Cpu);
  given.prepare(Backend::Cpu);
  EXPECT_GT(given.partitionCount(Backend::Cpu), byDefault.partitionCount(Backend::Cpu));
}

// A thin shell of the transfer function, far thinner than the step, on a field linear along the rays: point
// samples mostly step over it, pre-integration finds its optical depth exactly wherever a ray crosses it.
TEST_P(Integrator, PreintegrationFindsAShellThinnerThanTheStep) {
  // f runs from 0 to 1 over x in [-1, 1]; the function is opaque only for f in [0.49, 0.51], x in ±0.02.
  const Mesh mesh =
      buildMesh(makeBoxGrid(CellType::Tetra, 8, kBox, [](Vec3f p) { return 0.5f * (p.x + 1.f); }), "box");
  Renderer renderer(mesh, mesh.findField("f"), 64);
  const float alpha = 0.5f;
  ColorMap shell;
  shell.rgbPoints = {0.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f};
  shell.opacityPoints = {0.f,   0.f,   0.5f, 0.f, 0.4899f, 0.f, 0.5f, 0.f, 0.49f, alpha, 0.5f, 0.f,
                         0.51f, alpha, 0.5f, 0.f, 0.5101f, 0.f, 0.5f, 0.f, 1.f,   0.f,   0.5f, 0.f};
  renderer.setTransferFunction(TransferFunction(shell, 0.f, 1.f));
  Camera camera;
  camera.eye = {6.f, 0.1f, 0.2f};
  camera.at = {0.f, 0.f, 0.f};
  camera.up = {0.f, 0.f, 1.f};
  camera.fovy = 12.f;
  const float kappa = -std::log(1.f - alpha) / 0.1f;
  for (RenderMode mode : {RenderMode::Reference, RenderMode::Full}) {
    for (bool preintegrate : {false, true}) {
      RenderSettings settings = settingsFor(mode, 0.5f, 1.f);
      settings.integrator.preintegrate = preintegrate;
      const Frame frame = renderer.render(camera, settings);
      const CameraView view = makeCameraView(camera, settings.width, settings.height);
      int crossing = 0, right = 0;
      for (int y = 0; y < settings.height; ++y)
        for (int x = 0; x < settings.width; ++x) {
          const Ray ray = view.ray(x, y);
          // The ray's path through the slab |x| <= 0.02, where it lies inside the box.
          const float t0 = (0.02f - ray.origin.x) * ray.invDirection.x;
          const float t1 = (-0.02f - ray.origin.x) * ray.invDirection.x;
          const Vec3f p0 = ray.origin + ray.direction * t0, p1 = ray.origin + ray.direction * t1;
          auto inside = [](Vec3f p) { return std::fabs(p.y) < 0.95f && std::fabs(p.z) < 0.95f; };
          if (!inside(p0) || !inside(p1))
            continue;
          ++crossing;
          const float expected = 1.f - std::exp(-kappa * (t1 - t0) * length(ray.direction));
          right += std::fabs(frame.opacity[size_t(y * settings.width + x)] - expected) < 0.03f;
        }
      ASSERT_GT(crossing, 64 * 64 / 4);
      if (preintegrate)
        EXPECT_EQ(right, crossing) << modeName(mode);
      else
        EXPECT_LT(right, crossing / 2) << modeName(mode); // the test tells the two apart
    }
  }
}

namespace {

/// A camera 10 units down the x axis looking along +x through (y, z), with rays a few degrees apart.
Camera lookingAlongX(float y, float z) {
  Camera camera;
  camera.eye = {-10.f, y, z};
  camera.at = {0.f, y, z};
  camera.up = {0.f, 0.f, 1.f};
  camera.fovy = 2.2f;
  return camera;
}

/// The largest difference over a frame between each pixel's opacity and 1 - exp(-depth(distanceTo)), where
/// distanceTo(x) is how far along the pixel's ray (in world units) the plane at `x` lies.
template <class Depth>
float worstOpacityError(const Frame &frame, const RenderSettings &settings, const Camera &camera,
                        Depth depth) {
  const CameraView view = makeCameraView(camera, settings.width, settings.height);
  float worst = 0.f;
  for (int y = 0; y < settings.height; ++y)
    for (int x = 0; x < settings.width; ++x) {
      const Ray ray = view.ray(x, y);
      auto distanceTo = [&](float px) {
        return (px - ray.origin.x) * ray.invDirection.x * length(ray.direction);
      };
      const float expected = 1.f - std::exp(-depth(distanceTo));
      worst = std::max(worst, std::fabs(frame.opacity[size_t(y * settings.width + x)] - expected));
    }
  return worst;
}

} // namespace

// A cell field steps at the faces: pre-integration composites the segment that holds a step as two constant
// pieces split where the ray crosses the face, not as a linear ramp between the two samples' values (which
// with a sharp function puts the step at the wrong place). A slab of unit cubes (tets, hexahedra) with value
// 1 between two with value 0, rays near the cubes' axis that cross only the slab's faces near it, steps that
// straddle each face: the opacity is the slab's exactly.
TEST_P(Integrator, PreintegratedCellDataStepsAtTheFaces) {
  const Box3f box{{-2.f, -2.f, -2.f}, {2.f, 2.f, 2.f}};
  // Opaque only for values past 0.96: a ramp from 0 to 1 would be opaque over its last 4% alone.
  const float alpha = 0.1f;
  ColorMap sharp;
  sharp.rgbPoints = {0.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f};
  sharp.opacityPoints = {0.f,   0.f,   0.5f, 0.f, 0.95f, 0.f,   0.5f, 0.f,
                         0.96f, alpha, 0.5f, 0.f, 1.f,   alpha, 0.5f, 0.f};
  // Along x through the cubes of y, z in [0, 1]: a Kuhn tet's faces inside a cube lie where x - x0 equals y
  // or z, at least 0.3 from the cube's faces for y, z in [0.3, 0.7]; farther than a step.
  const Camera camera = lookingAlongX(0.5f, 0.5f);
  const float kappa = -std::log(1.f - alpha) / 0.1f;
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(
        makeBoxGrid(type, 4, box, [](Vec3f p) { return p.x > 0.f && p.x < 1.f ? 1.f : 0.f; }), "slab");
    Renderer renderer(mesh, mesh.findField("f_cell"), 64);
    renderer.setTransferFunction(TransferFunction(sharp, 0.f, 1.f));
    // Steps of 0.23: the faces at x = 0 and 1 fall within a segment, not on a sample.
    for (RenderMode mode : {RenderMode::Reference, RenderMode::Full}) {
      RenderSettings settings = settingsFor(mode, 0.23f);
      settings.integrator.preintegrate = true;
      const float worst =
          worstOpacityError(renderer.render(camera, settings), settings, camera,
                            [&](auto distanceTo) { return kappa * (distanceTo(1.f) - distanceTo(0.f)); });
      // A linear ramp is off by about 0.02 here.
      EXPECT_LT(worst, 1e-4f) << modeName(mode) << " " << int(type);
    }
  }
}

// Cells between two samples of a cell field are visited where they could show: a slab of cells thinner than
// the step, between a transparent field ahead and a faint one behind, is composited at its own opacity, where
// splitting the segment between its two samples' values would give it half the faint one's. The host's
// march only: the GPU's kernels keep the split (DeviceSampling).
TEST_P(Integrator, PreintegratedCellDataVisitsTheCellsBetweenSamples) {
  if (gBackend != Backend::Cpu)
    GTEST_SKIP() << "the GPU's kernels split the segment (DeviceSampling::kCellsBetweenSamples)";
  const Box3f box{{-2.f, -2.f, -2.f}, {2.f, 2.f, 2.f}};
  // 0 for x < 0, 1 in the slab 0 <= x < 0.25 (one cell thick), 0.5 behind it up to x = 1, 0 beyond.
  auto field = [](Vec3f p) { return p.x < 0.f || p.x >= 1.f ? 0.f : p.x < 0.25f ? 1.f : 0.5f; };
  const float slabAlpha = 0.3f, beyondAlpha = 0.05f; // per unit 0.1
  ColorMap map;
  map.rgbPoints = {0.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f};
  map.opacityPoints = {0.f,  0.f,         0.5f, 0.f, 0.4f, 0.f,       0.5f, 0.f,
                       0.5f, beyondAlpha, 0.5f, 0.f, 1.f,  slabAlpha, 0.5f, 0.f};
  const Camera camera = lookingAlongX(0.4f, 0.6f);
  const float kappaSlab = -std::log(1.f - slabAlpha) / 0.1f,
              kappaBeyond = -std::log(1.f - beyondAlpha) / 0.1f;
  for (CellType type : {CellType::Tetra, CellType::Hexahedron}) {
    const Mesh mesh = buildMesh(makeBoxGrid(type, 16, box, field), "thin slab");
    Renderer renderer(mesh, mesh.findField("f_cell"), 64);
    renderer.setTransferFunction(TransferFunction(map, 0.f, 1.f));
    // Reference: its march starts where the rays enter the mesh, in the transparent field. `full`'s begins
    // at the first partition drawn, at the slab, and leaves out what lies ahead of its first sample there.
    {
      const RenderMode mode = RenderMode::Reference;
      // Steps of 0.7, nearly three cells: the slab mostly lies between two samples.
      RenderSettings settings = settingsFor(mode, 0.7f);
      settings.integrator.preintegrate = true;
      const float worst =
          worstOpacityError(renderer.render(camera, settings), settings, camera, [&](auto distanceTo) {
            return kappaSlab * (distanceTo(0.25f) - distanceTo(0.f)) +
                   kappaBeyond * (distanceTo(1.f) - distanceTo(0.25f));
          });
      // Splitting the segments that hold the slab is off by about 0.24 here.
      EXPECT_LT(worst, 1e-3f) << modeName(mode) << " " << int(type);
    }
  }
}

// Each partition's step scale is its cells' size against the mesh's, as a power of two: cubes of half the
// edge (an eighth of the volume, 3 * 256 apart in log2) halve it.
TEST(Partitions, StepScalesAreTheCellSizeRatioAsAPowerOfTwo) {
  const int64_t mesh = -2000, half = mesh - 768, quarter = mesh - 2 * 768, twice = mesh + 768;
  const std::vector<uint64_t> counts{10, 10, 10, 10, 10};
  const std::vector<int64_t> sums{10 * mesh, 10 * half, 10 * quarter, 10 * twice, 10 * (mesh + 1000)};
  // Leaves 0-4 under a root with two inner nodes.
  std::vector<KdNode> nodes(9);
  nodes[0] = {0.f, 0, 1};
  nodes[1] = {0.f, 1, 3};
  nodes[2] = {0.f, 1, 5};
  nodes[3] = {0.f, KdNode::kLeaf, 0};
  nodes[4] = {0.f, 2, 7};
  nodes[5] = {0.f, KdNode::kLeaf, 3};
  nodes[6] = {0.f, KdNode::kLeaf, 4};
  nodes[7] = {0.f, KdNode::kLeaf, 1};
  nodes[8] = {0.f, KdNode::kLeaf, 2};
  const StepScales scales = computeStepScales(sums, counts, nodes);
  // The mesh's mean is mesh - 768 * 0.4 + 200 = mesh - 107: within half a power of two of leaf 0.
  EXPECT_EQ(scales.partition, (std::vector<float>{1.f, 0.5f, 0.25f, 2.f, 2.f}));
  EXPECT_EQ(scales.finest, 0.25f);
  EXPECT_EQ(scales.node[0], 2.f);
  EXPECT_EQ(scales.node[1], 1.f); // over leaves 0, 1 and 2
  EXPECT_EQ(scales.node[4], 0.5f);
  EXPECT_EQ(scales.node[2], 2.f);
}

// The pieces of a mesh split among processes: their shares of the step scales, each from its region's
// partitions over the cells that touch the region (as each rank holds them), give the whole mesh's
// reference exactly, on a graded mesh whose scales differ.
TEST(Partitions, PiecesStepScaleSharesMakeTheWholeMeshsReference) {
  Mesh graded = buildMesh(makeBoxGrid(CellType::Tetra, 16, kBox, [](Vec3f p) { return p.y; }), "graded");
  for (Vec3f &p : graded.points) // cells shrink towards x = -1, by a factor of 64 across the box
    p.x = -1.f + 2.f * (std::pow(64.f, 0.5f * (p.x + 1.f)) - 1.f) / 63.f;
  const auto piece = [&](const Box3f &region) {
    Mesh cells = graded;
    cells.tets.clear();
    for (size_t t = 0; t < graded.tets.size(); t += 4) {
      Box3f box;
      for (size_t k = 0; k < 4; ++k)
        box.extend(graded.points[graded.tets[t + k]]);
      if (!intersection(box, region).empty())
        cells.tets.insert(cells.tets.end(), graded.tets.begin() + ptrdiff_t(t),
                          graded.tets.begin() + ptrdiff_t(t + 4));
    }
    return detail::Access::make(std::move(cells), "piece");
  };
  const VolumeMesh mesh = detail::Access::make(Mesh(graded), "graded");
  for (uint32_t leafSize : {16u, 64u}) {
    const VolumeMesh::StepScaleReference whole = mesh.stepScaleReference(leafSize);
    EXPECT_LT(whole.finestStepScale, 1.f);
    for (int ranks : {2, 4}) {
      std::vector<VolumeMesh::StepScaleShare> shares;
      for (const Box3f &region : splitIntoRegions(mesh, ranks).regions)
        shares.push_back(piece(region).stepScaleShare(region, mesh.bounds(), leafSize));
      const VolumeMesh::StepScaleReference combined = VolumeMesh::stepScaleReference(shares);
      EXPECT_EQ(combined.meanCellSizeLog2, whole.meanCellSizeLog2) << ranks << " ranks, leaf " << leafSize;
      EXPECT_EQ(combined.finestStepScale, whole.finestStepScale) << ranks << " ranks, leaf " << leafSize;
    }
  }
}

// On a graded mesh, steps that follow the mesh take fewer samples where cells are large and more where they
// are small, and keep the analytic transmittance to within the longest step.
TEST_P(Integrator, LocalStepsFollowAGradedMesh) {
  Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 16, kBox, [](Vec3f) { return 0.5f; }), "graded");
  for (Vec3f &p : mesh.points) // cells shrink towards x = -1, by a factor of 64 across the box
    p.x = -1.f + 2.f * (std::pow(64.f, 0.5f * (p.x + 1.f)) - 1.f) / 63.f;
  Renderer renderer(mesh, mesh.findField("f"), 64);
  const float alphaPerUnit = 0.3f;
  renderer.setTransferFunction(TransferFunction(constantMap(alphaPerUnit), 0.f, 1.f));
  renderer.prepare(Backend::Cpu); // whose partitions the test reads
  renderer.prepare(gBackend);
  const Partitions &parts = renderer.partitions();
  const auto [finest, coarsest] = std::minmax_element(parts.stepScale.begin(), parts.stepScale.end());
  EXPECT_LE(*finest, 0.5f);
  EXPECT_GE(*coarsest, 2.f);
  EXPECT_EQ(parts.finestStepScale, *finest);
  RenderSettings global = settingsFor(RenderMode::Full, 0.02f, 0.02f);
  RenderSettings local = global;
  local.integrator.followMesh = true;
  expectExponentialTransmittance(renderer, local, alphaPerUnit, 0.02f * *coarsest, 1e-5f);
  const Frame a = renderer.render(obliqueCamera(), global), b = renderer.render(obliqueCamera(), local);
  EXPECT_NE(a.samplesTotal, b.samplesTotal);
}

// Where steps follow the mesh, a partition whose transfer function reaches kRefinedStepOpacity takes half its
// step: under a constant field (every partition at the largest adaptive step) an opacity just past it takes
// twice the samples of one just below it, and both keep the exact transmittance.
TEST_P(Integrator, OpaquePartitionsTakeHalfSteps) {
  Mesh mesh = buildMesh(makeBoxGrid(CellType::Tetra, 8, kBox, [](Vec3f) { return 0.5f; }), "uniform");
  Renderer renderer(mesh, mesh.findField("f"), 64);
  RenderSettings local = settingsFor(RenderMode::Full, 0.02f, 0.08f);
  local.integrator.followMesh = true;
  local.integrator.terminationOpacity = 2.f; // no ray ends early: the sample counts compare whole rays
  uint64_t samples[2];
  for (int opaque = 0; opaque < 2; ++opaque) {
    const float alphaPerUnit = opaque ? kRefinedStepOpacity + 0.05f : kRefinedStepOpacity - 0.05f;
    renderer.setTransferFunction(TransferFunction(constantMap(alphaPerUnit), 0.f, 1.f));
    expectExponentialTransmittance(renderer, local, alphaPerUnit, 0.08f, 1e-5f);
    samples[opaque] = renderer.render(obliqueCamera(), local).samplesTotal;
  }
  EXPECT_NEAR(double(samples[1]) / double(samples[0]), 2.0, 0.1);
}

// The default step from the median volume per tetrahedron, within [1e-4 x diagonal, thinnest side / 4]: a
// mesh of tiny cells cannot make rays of millions of samples, one of a few flat cells is sampled through (a
// single pyramid 6 x 6 x 3 rendered black at the step of its volume, 3.3), and empty bounds give 0.
TEST(DefaultStep, FollowsTheCellsWithinTheBounds) {
  const Box3f cube{{0.f, 0.f, 0.f}, {10.f, 10.f, 10.f}};
  VolumeStats stats;
  stats.medianPerTet = 1.0 / 8.0;
  EXPECT_FLOAT_EQ(defaultStepSize(stats, cube), 0.5f);
  stats.medianPerTet = 1e-18; // edge 1e-6
  EXPECT_FLOAT_EQ(defaultStepSize(stats, cube), 1e-4f * length(cube.size()));
  stats.medianPerTet = 36.0 / 2.0; // the pyramid
  EXPECT_FLOAT_EQ(defaultStepSize(stats, {{0.f, 0.f, 0.f}, {6.f, 6.f, 3.f}}), 0.75f);
  EXPECT_EQ(defaultStepSize(stats, Box3f{}), 0.f);
}
