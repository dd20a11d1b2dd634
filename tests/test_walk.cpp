// The tet walk that locates samples along a ray, with the weights a ray carries from sample to sample.
#include "mesh/cell.h"
#include "mesh/mesh.h"
#include "mesh/procedural_mesh.h"
#include "mesh/tet_affine.h"
#include "mesh/tet_neighbors.h"
#include "render/integrator.h"

#include <gtest/gtest.h>

#include <random>
#include <utility>
#include <vector>

using namespace uvr;

// Samples a short step apart along random rays, each located from the previous one's cell with the weights
// carried along the ray, land in a cell holding them and get the value that cell interpolates there: with
// the tets' corners read, as on the GPU, and with their affine records, as on the host.
TEST(WalkTets, CarriedWeightsGiveTheCellsOwnValues) {
  const Box3f box{{-1.f, -1.f, -1.f}, {1.f, 1.f, 1.f}};
  const Mesh mesh = buildMesh(makeBoxGrid(
                                  CellType::Tetra, 5, box, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f, 11),
                              "box");
  for (const auto [field, records] : {std::pair{0, false}, {-1, false}, {0, true}, {-1, true}}) {
    SCOPED_TRACE(testing::Message() << "field " << field << (records ? ", affine records" : ", corners"));
    const bool cellData = field < 0;
    const std::vector<uint32_t> neighbors = buildTetNeighbors(mesh);
    // Cell data: the cells' own index as their value, so that a value names its cell.
    std::vector<float> cellValues(mesh.tets.size() / 4);
    for (size_t c = 0; c < cellValues.size(); ++c)
      cellValues[c] = float(c);
    SceneView scene;
    scene.mesh = makeMeshView(mesh, field);
    if (cellData) {
      scene.mesh.values = cellValues.data();
      scene.mesh.cellCentered = true;
    }
    scene.tetNeighbors = neighbors.data();
    const std::vector<TetAffine> affine = records ? buildTetAffine(scene.mesh) : std::vector<TetAffine>{};
    scene.tetAffine = records ? affine.data() : nullptr;
    std::mt19937 random(2);
    std::uniform_real_distribution<float> u(-0.9f, 0.9f);
    int carried = 0, walked = 0;
    for (int r = 0; r < 200; ++r) {
      const Vec3f origin{u(random), u(random), u(random)};
      const Ray ray = makeRay(origin, normalize(Vec3f{u(random), u(random), u(random)}));
      float tEnter, tExit;
      ASSERT_TRUE(intersectBox(ray, box, 0.f, INFINITY, tEnter, tExit));
      RayCell at;
      for (uint32_t c = 0; c < scene.mesh.tetCount && at.cell == kNoCell; ++c)
        if (cellContains(scene.mesh, c, origin))
          at.cell = c;
      ASSERT_NE(at.cell, kNoCell);
      for (float t = 0.f; t < tExit; t += 0.05f) {
        float value;
        ASSERT_TRUE(walkTets(scene, ray, t, at.cell, 64, at, value)) << "ray " << r << " t " << t;
        const Vec3f p = ray.at(t);
        ASSERT_TRUE(cellContains(scene.mesh, at.cell, p));
        float expected;
        ASSERT_TRUE(sampleCell(scene.mesh, at.cell, p, expected));
        EXPECT_NEAR(value, expected, 1e-5f);
        (at.t < t ? carried : walked) += 1;
      }
    }
    // Most samples lie in the previous sample's tet here; the rest cross into a neighbour.
    EXPECT_GT(carried, walked);
    EXPECT_GT(walked, 200);
  }
}
