// VolumeRenderer::setField: new values on the same grid keep the acceleration data and render exactly as a
// renderer built for them; another grid is refused and changes nothing.
#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>
#include <uvr/system.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace uvr {
namespace {

const std::string kDisk = std::string(UVR_TEST_DATA) + "/../../data/disk_out_ref.vtu";

/// The grid of `mesh` as arrays, with one point field computed from the points by `value` and one cell field
/// of each cell's index: meshes made from it by fromArrays share their points and cells.
struct GridArrays {
  std::vector<float> points, pointValues, cellValues;
  std::vector<int64_t> offsets{0}, connectivity;
  std::vector<uint8_t> types;

  template <typename Value> GridArrays(const VolumeMesh &mesh, Value &&value) {
    for (const Vec3f &p : mesh.points()) {
      points.insert(points.end(), {p.x, p.y, p.z});
      pointValues.push_back(value(p));
    }
    for (CellType type : {CellType::Tetra, CellType::Pyramid, CellType::Wedge, CellType::Hexahedron}) {
      const std::span<const uint32_t> cells = mesh.cells(type);
      const size_t corners = type == CellType::Tetra     ? 4
                             : type == CellType::Pyramid ? 5
                             : type == CellType::Wedge   ? 6
                                                         : 8;
      for (size_t c = 0; c < cells.size() / corners; ++c) {
        connectivity.insert(connectivity.end(), cells.begin() + long(c * corners),
                            cells.begin() + long((c + 1) * corners));
        offsets.push_back(int64_t(connectivity.size()));
        types.push_back(uint8_t(type));
        cellValues.push_back(std::sin(0.01f * float(types.size())));
      }
    }
  }

  VolumeMesh mesh() const {
    MeshArrays arrays;
    arrays.points = ArrayView(points, 3);
    arrays.offsets = offsets;
    arrays.connectivity = connectivity;
    arrays.types = types;
    arrays.fields = {{"a", Centering::Point, ArrayView(pointValues)},
                     {"c", Centering::Cell, ArrayView(cellValues)}};
    return VolumeMesh::fromArrays(arrays, "grid");
  }
};

FrameSettings smallFrame(RenderMode mode) {
  FrameSettings settings;
  settings.mode = mode;
  settings.width = settings.height = 96;
  return settings;
}

Image render(VolumeRenderer &renderer, RenderMode mode, Backend backend = Backend::Cpu) {
  FrameSettings settings = smallFrame(mode);
  settings.backend = backend;
  const Camera camera = frameBounds(renderer.mesh().bounds(), "+x");
  return renderer.render(camera, settings).image;
}

void setFunction(VolumeRenderer &renderer, ValueRange range) {
  renderer.setTransferFunction(builtinColorMap("viridis"), range);
}

/// For each backend built and present: renders `before`, switches it to field `field` of `after` and checks
/// its frames against a renderer built for `after` from scratch, in every mode.
void expectSameAsFresh(const VolumeMesh &before, int beforeField, const VolumeMesh &after, int field,
                       ValueRange range) {
  for (Backend backend : {Backend::Cpu, Backend::Cuda}) {
    if (!backendAvailable(backend) || (backend == Backend::Cuda && cudaDeviceCount() == 0))
      continue;
    VolumeRenderer kept(before, beforeField);
    setFunction(kept, range);
    kept.prepare(backend);
    const Image old = render(kept, RenderMode::Full, backend);
    kept.setField(after, field);
    EXPECT_EQ(kept.fieldIndex(), field);
    VolumeRenderer fresh(after, field);
    setFunction(fresh, range);
    for (RenderMode mode :
         {RenderMode::Reference, RenderMode::Skip, RenderMode::Adaptive, RenderMode::Full}) {
      const FrameResult a = kept.render(frameBounds(after.bounds(), "+x"), [&] {
        FrameSettings s = smallFrame(mode);
        s.backend = backend;
        return s;
      }());
      const FrameResult b = fresh.render(frameBounds(after.bounds(), "+x"), [&] {
        FrameSettings s = smallFrame(mode);
        s.backend = backend;
        return s;
      }());
      EXPECT_EQ(a.image.rgb, b.image.rgb) << modeName(mode) << " on " << backendName(backend);
      EXPECT_EQ(a.stats.partitionsSkipped, b.stats.partitionsSkipped) << modeName(mode);
      EXPECT_EQ(a.stats.samplesTotal, b.stats.samplesTotal) << modeName(mode);
    }
    // The values did change what is drawn: the check above compares something.
    EXPECT_NE(old.rgb, render(fresh, RenderMode::Full, backend).rgb);
  }
}

TEST(SetField, NewValuesOnTheSameGridRenderAsAFreshBuild) {
  const VolumeMesh disk = VolumeMesh::load(kDisk);
  const GridArrays first(disk, [](Vec3f p) { return p.z; });
  const GridArrays second(disk, [](Vec3f p) { return std::cos(p.x) + p.z; });
  const VolumeMesh a = first.mesh(), b = second.mesh();
  ASSERT_EQ(a.points().size(), b.points().size());
  const ValueRange range{-3.f, 10.f};
  expectSameAsFresh(a, 0, b, 0, range);
}

TEST(SetField, AnotherFieldOfTheSameMeshAndCellData) {
  const VolumeMesh disk = VolumeMesh::load(kDisk);
  const int temp = disk.chooseField("Temp"), pres = disk.chooseField("Pres");
  expectSameAsFresh(disk, temp, disk, pres, disk.fieldRange(pres));
  // From a point field to a cell field and back.
  const GridArrays grid(disk, [](Vec3f p) { return p.x * p.y; });
  const VolumeMesh mesh = grid.mesh();
  expectSameAsFresh(mesh, 0, mesh, 1, {-1.f, 1.f});
  expectSameAsFresh(mesh, 1, mesh, 0, {-1.f, 1.f});
}

TEST(SetField, AnotherGridIsRefusedAndChangesNothing) {
  const VolumeMesh disk = VolumeMesh::load(kDisk);
  const GridArrays grid(disk, [](Vec3f p) { return p.z; });
  GridArrays moved = grid;
  moved.points[0] += 1e-3f;
  VolumeRenderer renderer(grid.mesh(), 0);
  setFunction(renderer, {-3.f, 10.f});
  const Image before = render(renderer, RenderMode::Full);
  try {
    renderer.setField(moved.mesh(), 0);
    ADD_FAILURE() << "a moved point was accepted";
  } catch (const Error &e) {
    EXPECT_NE(std::string(e.what()).find("differ"), std::string::npos) << e.what();
  }
  EXPECT_THROW(renderer.setField(grid.mesh(), 5), Error);
  EXPECT_THROW(
      renderer.setField(VolumeMesh::load(std::string(UVR_TEST_DATA) + "/vtk/pyramid__ascii_v51.vtk"), 0),
      Error);
  EXPECT_EQ(renderer.fieldIndex(), 0);
  EXPECT_EQ(render(renderer, RenderMode::Full).rgb, before.rgb);
}

} // namespace
} // namespace uvr
