// Uses uvr through its installed interface alone: builds a mesh from arrays (as a VTK mapper hands them
// over) and loads one from a file, renders each, and checks that the volume shows.
#include <uvr/uvr.h>

#include <cstdint>
#include <cstdio>
#include <vector>

namespace {

/// Whether some pixel differs from the background and some ray gathered opacity.
bool drawsSomething(uvr::VolumeRenderer &renderer, const uvr::ColorMap &map) {
  const uvr::VolumeMesh &mesh = renderer.mesh();
  renderer.setTransferFunction(map, mesh.fieldRange(renderer.fieldIndex()));
  uvr::FrameSettings settings;
  settings.width = settings.height = 64;
  settings.background = {0.f, 0.f, 0.f};
  const uvr::FrameResult frame = renderer.render(uvr::frameBounds(mesh.bounds()), settings);
  bool colored = false, opaque = false;
  for (uint8_t value : frame.image.rgb)
    colored = colored || value != 0;
  for (float alpha : frame.opacity)
    opaque = opaque || alpha > 0.f;
  std::printf("%s: %llu cells, %.1f samples/pixel, %u partitions\n", mesh.source().c_str(),
              static_cast<unsigned long long>(mesh.cellCount()), frame.stats.samplesPerPixelMean,
              frame.stats.partitions);
  return colored && opaque && frame.stats.samplesTotal > 0;
}

} // namespace

int main(int argc, char **argv) {
  try {
    // A unit cube as one hexahedron and a tetrahedron on top of it, with a point field.
    const std::vector<float> points = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1,    0,    0, 0,
                                       1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 0.5f, 0.5f, 2};
    const std::vector<int64_t> offsets = {0, 8, 12};
    const std::vector<int64_t> connectivity = {0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 8};
    const std::vector<uint8_t> types = {uint8_t(uvr::CellType::Hexahedron), uint8_t(uvr::CellType::Tetra)};
    const std::vector<double> heat = {0, 1, 2, 1, 1, 2, 3, 2, 4};
    uvr::MeshArrays arrays;
    arrays.points = uvr::ArrayView(points, 3);
    arrays.offsets = offsets;
    arrays.connectivity = connectivity;
    arrays.types = types;
    arrays.fields.push_back({"heat", uvr::Centering::Point, uvr::ArrayView(heat)});
    const uvr::VolumeMesh built = uvr::VolumeMesh::fromArrays(arrays, "arrays");
    const uvr::CellCounts counts = built.cellCounts();
    if (built.pointCount() != 9 || counts.hex != 1 || counts.tet != 1) {
      std::fprintf(stderr, "uvr_consumer: the mesh from arrays has the wrong counts\n");
      return 1;
    }
    uvr::VolumeRenderer fromArrays(built, built.chooseField("heat"));
    if (!drawsSomething(fromArrays, uvr::chooseColorMap("viridis"))) {
      std::fprintf(stderr, "uvr_consumer: the mesh from arrays rendered nothing\n");
      return 1;
    }
    if (argc > 1) {
      const uvr::VolumeMesh loaded = uvr::VolumeMesh::load(argv[1]);
      uvr::VolumeRenderer fromFile(loaded, loaded.chooseField(""));
      const std::vector<uvr::Vec4f> table = {{0.f, 0.f, 1.f, 0.2f}, {1.f, 0.f, 0.f, 1.f}};
      if (!drawsSomething(fromFile, uvr::colorMapFromTable(table))) {
        std::fprintf(stderr, "uvr_consumer: %s rendered nothing\n", argv[1]);
        return 1;
      }
    }
  } catch (const uvr::Error &e) {
    std::fprintf(stderr, "uvr_consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
