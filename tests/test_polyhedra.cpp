// Polyhedra (VTK type 42) in .vtu and legacy .vtk files, decomposed on load: hand-written files render as
// their twins of hexahedra and wedges, malformed ones are refused. And fields named by their centring
// ("point:p", "cell:p") in every reader that can hold both.
#include "io/mesh_io.h"
#include "mesh/polyhedra.h"
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/image.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

using namespace uvr;

namespace {

namespace fs = std::filesystem;

using Face = std::vector<int64_t>;
using Faces = std::vector<Face>;

/// A small grid to write: points, cells (a polyhedron's point list and faces), point and cell fields.
struct TestGrid {
  std::vector<Vec3f> points;
  std::vector<std::vector<int64_t>> cells; ///< point indices (for a polyhedron: its distinct points)
  std::vector<int> types;
  std::vector<Faces> faces; ///< per cell; empty but for polyhedra
  std::vector<std::pair<std::string, std::vector<float>>> pointFields, cellFields;

  void add(int type, std::vector<int64_t> ids, Faces cellFaces = {}) {
    cells.push_back(std::move(ids));
    types.push_back(type);
    faces.push_back(std::move(cellFaces));
  }
};

/// The faces of a hexahedron in VTK's corner order, each turning outward.
Faces hexFaces(const std::array<int64_t, 8> &v) {
  return {{v[0], v[3], v[2], v[1]}, {v[4], v[5], v[6], v[7]}, {v[0], v[1], v[5], v[4]},
          {v[1], v[2], v[6], v[5]}, {v[2], v[3], v[7], v[6]}, {v[3], v[0], v[4], v[7]}};
}

float linearField(Vec3f p) { return p.x + 2.f * p.y + 3.f * p.z; }

/// n x n x n hexahedra on [0, 1]^3, each a hexahedron or (where `poly` says) the same cell as a polyhedron;
/// `inward` turns every other face of the polyhedra inward. Point field f (linear), cell field g.
TestGrid cubeGrid(int n, const std::function<bool(int)> &poly, bool inward = false) {
  TestGrid grid;
  const int m = n + 1;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i)
        grid.points.push_back({float(i) / float(n), float(j) / float(n), float(k) / float(n)});
  std::vector<float> g;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        auto at = [&](int di, int dj, int dk) { return int64_t((k + dk) * m * m + (j + dj) * m + i + di); };
        const std::array<int64_t, 8> v = {at(0, 0, 0), at(1, 0, 0), at(1, 1, 0), at(0, 1, 0),
                                          at(0, 0, 1), at(1, 0, 1), at(1, 1, 1), at(0, 1, 1)};
        const int c = int(grid.cells.size());
        g.push_back(float(c % 3));
        if (!poly(c)) {
          grid.add(12, {v.begin(), v.end()});
          continue;
        }
        Faces faces = hexFaces(v);
        if (inward)
          for (size_t f = 0; f < faces.size(); f += 2)
            std::reverse(faces[f].begin(), faces[f].end());
        grid.add(42, {v.begin(), v.end()}, faces);
      }
  std::vector<float> f;
  for (Vec3f p : grid.points)
    f.push_back(linearField(p));
  grid.pointFields = {{"f", f}};
  grid.cellFields = {{"g", g}};
  return grid;
}

/// A pentagonal prism and a wedge beside it, as polyhedra or as their twins (three wedges and a wedge).
TestGrid prismGrid(bool poly) {
  TestGrid grid;
  for (int level = 0; level < 2; ++level)
    for (int i = 0; i < 5; ++i) {
      const float a = 2.f * float(M_PI) * float(i) / 5.f;
      grid.points.push_back({std::cos(a), std::sin(a), float(level)});
    }
  // The wedge stands on the prism's face 0-1 outside it.
  grid.points.push_back({1.4f, 0.7f, 0.f});
  grid.points.push_back({1.4f, 0.7f, 1.f});
  if (poly) {
    Faces faces = {{0, 4, 3, 2, 1}, {5, 6, 7, 8, 9}};
    for (int i = 0; i < 5; ++i)
      faces.push_back({i, (i + 1) % 5, 5 + (i + 1) % 5, 5 + i});
    grid.add(42, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}, faces);
    grid.add(42, {0, 1, 10, 5, 6, 11},
             {{0, 1, 10}, {5, 11, 6}, {0, 5, 6, 1}, {1, 6, 11, 10}, {10, 11, 5, 0}});
  } else {
    grid.add(13, {0, 1, 2, 5, 6, 7});
    grid.add(13, {0, 2, 3, 5, 7, 8});
    grid.add(13, {0, 3, 4, 5, 8, 9});
    grid.add(13, {0, 1, 10, 5, 6, 11});
  }
  std::vector<float> f;
  for (Vec3f p : grid.points)
    f.push_back(linearField(p));
  grid.pointFields = {{"f", f}};
  grid.cellFields = {{"g", std::vector<float>(grid.cells.size(), 7.f)}};
  return grid;
}

template <typename T> std::string joined(const std::vector<T> &values) {
  std::ostringstream text;
  for (const T &v : values)
    text << v << ' ';
  return text.str();
}

std::vector<int64_t> faceStream(const Faces &faces) {
  std::vector<int64_t> stream{int64_t(faces.size())};
  for (const Face &face : faces) {
    stream.push_back(int64_t(face.size()));
    stream.insert(stream.end(), face.begin(), face.end());
  }
  return stream;
}

enum class VtuFaces { Stream, Vtk94 };

/// An ascii .vtu. VtuFaces::Stream: `faces` and `faceoffsets`; Vtk94: face_connectivity, face_offsets,
/// polyhedron_to_faces, polyhedron_offsets, faces shared between cells where they have the same points.
std::string vtuText(const TestGrid &g, VtuFaces layout = VtuFaces::Stream) {
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
       "byte_order=\"LittleEndian\">\n"
    << "<UnstructuredGrid><Piece NumberOfPoints=\"" << g.points.size() << "\" NumberOfCells=\""
    << g.cells.size() << "\">\n<PointData>\n";
  for (const auto &[name, values] : g.pointFields)
    x << "<DataArray type=\"Float32\" Name=\"" << name << "\" format=\"ascii\">" << joined(values)
      << "</DataArray>\n";
  x << "</PointData>\n<CellData>\n";
  for (const auto &[name, values] : g.cellFields)
    x << "<DataArray type=\"Float32\" Name=\"" << name << "\" format=\"ascii\">" << joined(values)
      << "</DataArray>\n";
  x << "</CellData>\n<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">";
  for (Vec3f p : g.points)
    x << p.x << ' ' << p.y << ' ' << p.z << ' ';
  x << "</DataArray></Points>\n<Cells>\n";
  std::vector<int64_t> connectivity, offsets;
  for (const auto &cell : g.cells) {
    connectivity.insert(connectivity.end(), cell.begin(), cell.end());
    offsets.push_back(int64_t(connectivity.size()));
  }
  auto array = [&](const char *name, const std::string &values) {
    x << "<DataArray type=\"Int64\" Name=\"" << name << "\" format=\"ascii\">" << values << "</DataArray>\n";
  };
  array("connectivity", joined(connectivity));
  array("offsets", joined(offsets));
  x << "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" << joined(g.types) << "</DataArray>\n";
  bool anyPoly = false;
  for (int type : g.types)
    anyPoly |= type == 42;
  if (anyPoly && layout == VtuFaces::Stream) {
    std::vector<int64_t> stream, faceOffsets;
    for (size_t c = 0; c < g.cells.size(); ++c) {
      if (g.types[c] != 42) {
        faceOffsets.push_back(-1);
        continue;
      }
      const std::vector<int64_t> s = faceStream(g.faces[c]);
      stream.insert(stream.end(), s.begin(), s.end());
      faceOffsets.push_back(int64_t(stream.size()));
    }
    array("faces", joined(stream));
    array("faceoffsets", joined(faceOffsets));
  } else if (anyPoly) {
    std::vector<Face> shared; // sorted point lists of the faces so far, to share them
    std::vector<int64_t> faceConnectivity, faceOffsets, cellFaces, cellOffsets;
    for (size_t c = 0; c < g.cells.size(); ++c) {
      for (const Face &face : g.faces[c]) {
        Face key = face;
        std::sort(key.begin(), key.end());
        auto found = std::find(shared.begin(), shared.end(), key);
        if (found == shared.end()) {
          shared.push_back(key);
          faceConnectivity.insert(faceConnectivity.end(), face.begin(), face.end());
          faceOffsets.push_back(int64_t(faceConnectivity.size()));
          found = shared.end() - 1;
        }
        cellFaces.push_back(found - shared.begin());
      }
      cellOffsets.push_back(int64_t(cellFaces.size()));
    }
    array("face_connectivity", joined(faceConnectivity));
    array("face_offsets", joined(faceOffsets));
    array("polyhedron_to_faces", joined(cellFaces));
    array("polyhedron_offsets", joined(cellOffsets));
  }
  x << "</Cells>\n</Piece></UnstructuredGrid></VTKFile>\n";
  return x.str();
}

/// A legacy .vtk, version 4.2 (CELLS n size) or 5.1 (OFFSETS, CONNECTIVITY), ascii or binary (big-endian, as
/// VTK writes it); cell data before point data when `cellDataFirst`. A polyhedron's entry is its face stream.
std::string vtkText(const TestGrid &g, bool version51, bool cellDataFirst = false, bool binary = false) {
  std::ostringstream x;
  auto put = [&](auto value) {
    if (!binary) {
      x << value << ' ';
      return;
    }
    char bytes[sizeof(value)];
    std::memcpy(bytes, &value, sizeof(value));
    for (size_t i = sizeof(value); i-- > 0;)
      x.put(bytes[i]);
  };
  x << "# vtk DataFile Version " << (version51 ? "5.1" : "4.2") << "\ntest\n"
    << (binary ? "BINARY" : "ASCII") << "\nDATASET UNSTRUCTURED_GRID\nPOINTS " << g.points.size()
    << " float\n";
  for (Vec3f p : g.points) {
    put(p.x);
    put(p.y);
    put(p.z);
  }
  x << '\n';
  std::vector<std::vector<int64_t>> entries;
  size_t size = 0;
  for (size_t c = 0; c < g.cells.size(); ++c) {
    entries.push_back(g.types[c] == 42 ? faceStream(g.faces[c]) : g.cells[c]);
    size += entries.back().size();
  }
  if (version51) {
    std::vector<int64_t> offsets{0}, connectivity;
    for (const auto &e : entries) {
      connectivity.insert(connectivity.end(), e.begin(), e.end());
      offsets.push_back(int64_t(connectivity.size()));
    }
    x << "CELLS " << offsets.size() << ' ' << connectivity.size() << "\nOFFSETS vtktypeint64\n";
    for (int64_t v : offsets)
      put(v);
    x << "\nCONNECTIVITY vtktypeint64\n";
    for (int64_t v : connectivity)
      put(v);
  } else {
    x << "CELLS " << entries.size() << ' ' << size + entries.size() << '\n';
    for (const auto &e : entries) {
      put(int32_t(e.size()));
      for (int64_t v : e)
        put(int32_t(v));
    }
  }
  x << "\nCELL_TYPES " << g.types.size() << '\n';
  for (int type : g.types)
    put(int32_t(type));
  x << '\n';
  auto data = [&](const char *section, size_t count, const auto &fields) {
    x << section << ' ' << count << '\n';
    for (const auto &[name, values] : fields) {
      x << "SCALARS " << name << " float\nLOOKUP_TABLE default\n";
      for (float v : values)
        put(v);
      x << '\n';
    }
  };
  if (cellDataFirst) {
    data("CELL_DATA", g.cells.size(), g.cellFields);
    data("POINT_DATA", g.points.size(), g.pointFields);
  } else {
    data("POINT_DATA", g.points.size(), g.pointFields);
    data("CELL_DATA", g.cells.size(), g.cellFields);
  }
  return x.str();
}

class Polyhedra : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("uvr_poly_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string &name, const std::string &text) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }

  /// Expects loading `text` as `name` to throw uvr::Error saying `message`.
  void expectRefused(const std::string &name, const std::string &text, const std::string &message) const {
    const std::string path = write(name, text);
    try {
      VolumeMesh::load(path);
      ADD_FAILURE() << name << " was accepted, expected: " << message;
    } catch (const Error &e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }

  fs::path dir_;
};

/// `field` of `mesh` rendered obliquely with a fixed step (the default step follows the cell volumes, which
/// the decomposition changes).
Image render(const VolumeMesh &mesh, const std::string &field) {
  VolumeRenderer renderer(mesh, mesh.chooseField(field));
  const int index = mesh.chooseField(field);
  renderer.setTransferFunction(builtinColorMap("Cool to Warm"), defaultTransferRange(mesh.fieldRange(index)));
  Camera camera;
  const Box3f b = mesh.bounds();
  camera.at = (b.lower + b.upper) * 0.5f;
  camera.eye = camera.at + Vec3f{2.1f, 1.6f, 2.9f} * length(b.upper - b.lower) * 0.7f;
  camera.fovy = 35.f;
  FrameSettings settings;
  settings.mode = RenderMode::Reference;
  settings.width = settings.height = 160;
  settings.s1 = 0.004f * length(b.upper - b.lower);
  settings.unit = 0.1f * length(b.upper - b.lower);
  return renderer.render(camera, settings).image;
}

void expectSameImages(const VolumeMesh &a, const VolumeMesh &b, const std::string &field) {
  const Image x = render(a, field), y = render(b, field);
  EXPECT_GE(ssim(x, y), 0.999) << a.source() << " vs " << b.source() << ", field " << field;
}

/// Every kept cell has positive volume (tets and pyramids: the pieces of polyhedra).
void expectPositiveVolumes(const VolumeMesh &mesh) {
  const auto p = mesh.points();
  const auto tets = mesh.cells(CellType::Tetra);
  for (size_t i = 0; i < tets.size(); i += 4)
    EXPECT_GT(
        dot(p[tets[i + 1]] - p[tets[i]], cross(p[tets[i + 2]] - p[tets[i]], p[tets[i + 3]] - p[tets[i]])),
        0.f);
  const auto pyramids = mesh.cells(CellType::Pyramid);
  for (size_t i = 0; i < pyramids.size(); i += 5) {
    const uint32_t *v = &pyramids[i];
    const Vec3f base = (p[v[0]] + p[v[1]] + p[v[2]] + p[v[3]]) * 0.25f;
    EXPECT_GT(dot(cross(p[v[2]] - p[v[0]], p[v[3]] - p[v[1]]), p[v[4]] - base), 0.f);
  }
}

TEST_F(Polyhedra, HexahedraAsPolyhedraRenderAsHexahedra) {
  const TestGrid twin = cubeGrid(3, [](int) { return false; });
  const VolumeMesh reference = VolumeMesh::load(write("twin.vtu", vtuText(twin)));
  struct Variant {
    std::string name, text;
  };
  const TestGrid all = cubeGrid(3, [](int) { return true; });
  const TestGrid some = cubeGrid(3, [](int c) { return c % 2 == 0; });
  const TestGrid inward = cubeGrid(
      3, [](int) { return true; }, true);
  const std::vector<Variant> variants = {
      {"all.vtu", vtuText(all)},
      {"some.vtu", vtuText(some)},
      {"inward.vtu", vtuText(inward)},
      {"vtk94.vtu", vtuText(all, VtuFaces::Vtk94)},
      {"some94.vtu", vtuText(some, VtuFaces::Vtk94)},
      {"all42.vtk", vtkText(all, false)},
      {"all51.vtk", vtkText(all, true)},
      {"inward51.vtk", vtkText(inward, true)},
      {"some_binary42.vtk", vtkText(some, false, false, true)},
      {"binary51.vtk", vtkText(inward, true, true, true)},
  };
  for (const Variant &v : variants) {
    SCOPED_TRACE(v.name);
    const VolumeMesh mesh = VolumeMesh::load(write(v.name, v.text));
    const CellCounts counts = mesh.cellCounts();
    const uint64_t polyhedra = v.name.starts_with("some") ? 14 : 27;
    EXPECT_EQ(counts.polyhedron, polyhedra);
    EXPECT_EQ(counts.polyhedronPyramids, 6 * polyhedra);
    EXPECT_EQ(counts.polyhedronTets, 0u);
    EXPECT_EQ(counts.pyramid, 6 * polyhedra);
    EXPECT_EQ(counts.hex, 27 - polyhedra);
    EXPECT_EQ(counts.inverted, 0u);
    EXPECT_EQ(mesh.pointCount(), 64 + polyhedra); // a centre per polyhedron
    expectPositiveVolumes(mesh);
    // The centre's value is the average of the corners': exact for a linear field.
    const int f = mesh.findField("f");
    const auto points = mesh.points();
    const auto values = mesh.fieldValues(f);
    for (size_t i = 0; i < points.size(); ++i)
      ASSERT_NEAR(values[i], linearField(points[i]), 1e-5f);
    expectSameImages(reference, mesh, "f");
    expectSameImages(reference, mesh, "g");
  }
}

TEST_F(Polyhedra, PentagonalPrismAndWedgeRenderAsWedges) {
  const VolumeMesh twin = VolumeMesh::load(write("twin.vtu", vtuText(prismGrid(false))));
  for (const auto &[name, text] : std::vector<std::pair<std::string, std::string>>{
           {"poly.vtu", vtuText(prismGrid(true))},
           {"poly94.vtu", vtuText(prismGrid(true), VtuFaces::Vtk94)},
           {"poly42.vtk", vtkText(prismGrid(true), false)},
           {"poly51.vtk", vtkText(prismGrid(true), true)}}) {
    SCOPED_TRACE(name);
    const VolumeMesh mesh = VolumeMesh::load(write(name, text));
    const CellCounts counts = mesh.cellCounts();
    EXPECT_EQ(counts.polyhedron, 2u);
    // Pentagons: 3 triangles each; the wedge's triangles 1 each; 5 + 3 quads.
    EXPECT_EQ(counts.polyhedronTets, 8u);
    EXPECT_EQ(counts.polyhedronPyramids, 8u);
    EXPECT_EQ(counts.tet + counts.pyramid, 16u);
    EXPECT_EQ(counts.wedge + counts.hex, 0u);
    EXPECT_EQ(counts.inverted, 0u);
    expectPositiveVolumes(mesh);
    const int g = mesh.findField("g");
    for (float value : mesh.fieldValues(g))
      EXPECT_EQ(value, 7.f);
    expectSameImages(twin, mesh, "f");
    expectSameImages(twin, mesh, "g");
  }
}

/// `text` with the last `from` replaced by `to`.
std::string replacedLast(std::string text, const std::string &from, const std::string &to) {
  const size_t at = text.rfind(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

/// `text` with every `from` replaced by `to`.
std::string replacedAll(std::string text, const std::string &from, const std::string &to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

TEST_F(Polyhedra, CentresTakeTheCellFieldOfTheirName) {
  // The prism and wedge as polyhedra, with point fields p (a cell field p too), U (3 components at points
  // and at cells), q (no cell field) and r (a cell field r of 2 components).
  TestGrid grid = prismGrid(true);
  const std::vector<float> f = grid.pointFields[0].second;
  std::vector<float> u;
  for (float v : f)
    u.insert(u.end(), {v, 0.f, 0.f});
  grid.pointFields = {{"p", f}, {"U", u}, {"q", f}, {"r", f}};
  grid.cellFields = {
      {"p", {50.f, 60.f}}, {"U", {3.f, 4.f, 0.f, 0.f, 0.f, -12.f}}, {"r", {1.f, 1.f, 2.f, 2.f}}};
  const float cellP[] = {50.f, 60.f}, cellU[] = {5.f, 12.f};
  auto vtu = [&](VtuFaces layout) {
    const std::string text =
        replacedAll(vtuText(grid, layout), "Name=\"U\"", "Name=\"U\" NumberOfComponents=\"3\"");
    return replacedLast(text, "Name=\"r\"", "Name=\"r\" NumberOfComponents=\"2\"");
  };
  auto vtk = [&](bool version51) {
    const std::string text =
        replacedAll(vtkText(grid, version51), "SCALARS U float\n", "SCALARS U float 3\n");
    return replacedLast(text, "SCALARS r float\n", "SCALARS r float 2\n");
  };
  // Each polyhedron's centre: the average of its distinct points.
  std::vector<Vec3f> centres;
  for (const auto &cell : grid.cells) {
    Vec3f sum{0.f, 0.f, 0.f};
    for (int64_t id : cell)
      sum = sum + grid.points[size_t(id)];
    centres.push_back(sum * (1.f / float(cell.size())));
  }
  for (const auto &[name, text] :
       std::vector<std::pair<std::string, std::string>>{{"poly.vtu", vtu(VtuFaces::Stream)},
                                                        {"poly94.vtu", vtu(VtuFaces::Vtk94)},
                                                        {"poly42.vtk", vtk(false)},
                                                        {"poly51.vtk", vtk(true)}}) {
    SCOPED_TRACE(name);
    const VolumeMesh mesh = VolumeMesh::load(write(name, text));
    const auto points = mesh.points();
    ASSERT_EQ(points.size(), grid.points.size() + 2);
    const auto values = [&](const std::string &field) {
      const int index = mesh.findField(field);
      EXPECT_GE(index, 0) << field;
      EXPECT_EQ(mesh.field(index).centering, Centering::Point) << field;
      return mesh.fieldValues(index);
    };
    const auto p = values("point:p"), U = values("point:U"), q = values("point:q"), r = values("point:r");
    int found = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const float linear = linearField(points[i]);
      const auto centre = std::find_if(centres.begin(), centres.end(),
                                       [&](Vec3f c) { return length(points[i] - c) <= 1e-5f; });
      if (centre == centres.end()) {
        EXPECT_NEAR(p[i], linear, 1e-5f);
        EXPECT_NEAR(U[i], std::abs(linear), 1e-5f);
        continue;
      }
      const size_t k = size_t(centre - centres.begin());
      ++found;
      EXPECT_EQ(p[i], cellP[k]) << "centre " << k;
      EXPECT_FLOAT_EQ(U[i], cellU[k]) << "centre " << k; // the magnitude of the cell's vector
      // The corners' average: exact for a linear field at the corners' centre.
      EXPECT_NEAR(q[i], linear, 1e-5f) << "centre " << k;
      EXPECT_NEAR(r[i], linear, 1e-5f) << "centre " << k;
    }
    EXPECT_EQ(found, 2);
  }
}

TEST_F(Polyhedra, InfoCountsSurviveSeriesAndLegacyTogether) {
  // A .pvd of two parts: one polyhedral .vtu and one legacy file.
  write("a.vtu", vtuText(prismGrid(true)));
  write("b.vtu", vtuText(cubeGrid(1, [](int) { return true; })));
  const std::string pvd = write("s.pvd", "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\"><Collection>"
                                         "<DataSet timestep=\"0\" file=\"a.vtu\"/>"
                                         "<DataSet timestep=\"0\" file=\"b.vtu\"/></Collection></VTKFile>\n");
  const CellCounts counts = VolumeMesh::load(pvd).cellCounts();
  EXPECT_EQ(counts.polyhedron, 3u);
  EXPECT_EQ(counts.polyhedronTets, 8u);
  EXPECT_EQ(counts.polyhedronPyramids, 14u);
}

TEST_F(Polyhedra, MalformedPolyhedraAreRefused) {
  const TestGrid good = prismGrid(true);
  const std::string goodVtu = vtuText(good);
  const std::string goodVtk = vtkText(good, false);
  auto replaced = [](std::string text, const std::string &from, const std::string &to) {
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? text : text.replace(at, from.size(), to);
  };
  // The first polyhedron's stream starts "7 5 0 4 3 2 1 5 5 6 7 8 9": 7 faces, a pentagon, ...
  const std::string stream = "7 5 0 4 3 2 1 5 5 6 7 8 9";
  // Errors name the file's cell as the position.
  expectRefused("count.vtu", replaced(goodVtu, stream, "700000000 5 0 4 3 2 1 5 5 6 7 8 9"),
                "cell 0: polyhedron of 700000000 faces in a face stream of 38 entries");
  expectRefused("count.vtk", replaced(goodVtk, stream, "700000000 5 0 4 3 2 1 5 5 6 7 8 9"),
                "cell 0: polyhedron of 700000000 faces in a face stream of 38 entries");
  expectRefused("facesize.vtu", replaced(goodVtu, stream, "7 5 0 4 3 2 1 5 5 6 7 8 900000"),
                "outside [0, 12)");
  expectRefused("index.vtk", replaced(goodVtk, stream, "7 5 0 4 3 2 1 5 5 6 7 8 -1"),
                "cell 0: point index -1 of a face outside [0, 12)");
  expectRefused("longface.vtu", replaced(goodVtu, stream, "7 5 0 4 3 2 1 99 5 6 7 8 9"),
                "more than its face stream holds");
  expectRefused("shortface.vtk", replaced(goodVtk, stream, "7 5 0 4 3 2 1 2 5 6 7 8 9"), "fewer than 3");
  expectRefused("nofaces.vtk", replaced(goodVtk, stream, "0 5 0 4 3 2 1 5 5 6 7 8 9"), "face count");
  // faceoffsets: the first polyhedron's stream ends at 38 (1 + 2 * 6 + 5 * 5), the second at 62.
  expectRefused("offsets.vtu", replaced(goodVtu, ">38 62 <", ">38 30 <"), "does not follow");
  expectRefused("offsetsbig.vtu", replaced(goodVtu, ">38 62 <", ">38 6200000000 <"), "too short");
  expectRefused("nofacearrays.vtu", replaced(goodVtu, "Name=\"faceoffsets\"", "Name=\"other\""),
                "without their faces");
  // One point repeated: no volume to decompose.
  TestGrid flat;
  flat.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  flat.add(42, {0, 1, 2}, {{0, 1, 2}, {0, 2, 1}, {0, 1, 2}, {2, 1, 0}});
  expectRefused("flat.vtu", vtuText(flat), "distinct points");
  // VTK 9.4's shared faces: a face id past the faces, and one face in three cells.
  const std::string good94 = vtuText(cubeGrid(1, [](int) { return true; }), VtuFaces::Vtk94);
  expectRefused("faceid.vtu", replaced(good94, ">0 1 2 3 4 5 <", ">0 1 2 3 4 -5 <"), "negative");
  TestGrid three = cubeGrid(1, [](int) { return true; });
  three.add(42, three.cells[0], three.faces[0]);
  three.add(42, three.cells[0], three.faces[0]);
  three.cellFields[0].second = {0.f, 1.f, 2.f};
  expectRefused("thrice.vtu", vtuText(three, VtuFaces::Vtk94), "more than two polyhedra");
}

#if UVR_HAVE_NETCDF
/// Exodus II NFACED: a hexahedron and a pentagonal prism beside it (a house's shape, extruded) as polyhedra
/// over one NSIDED face block, the square between them shared; nodal and element variables t and u, u
/// without values in the block (NaN there).
const char *kNfacedCdl = R"(netcdf nfaced {
dimensions:
	len_name = 33 ;
	time_step = UNLIMITED ;
	num_dim = 3 ;
	num_nodes = 14 ;
	num_elem = 2 ;
	num_el_blk = 1 ;
	num_fa_blk = 1 ;
	num_fa_in_blk1 = 12 ;
	num_nod_per_fa1 = 50 ;
	num_el_in_blk1 = 2 ;
	num_fac_per_el1 = 13 ;
	num_nod_var = 2 ;
	num_elem_var = 2 ;
variables:
	float time_whole(time_step) ;
	int eb_prop1(num_el_blk) ;
	int fa_prop1(num_fa_blk) ;
	float coordx(num_nodes) ;
	float coordy(num_nodes) ;
	float coordz(num_nodes) ;
	int fbconn1(num_nod_per_fa1) ;
		fbconn1:elem_type = "nsided" ;
	int fbepecnt1(num_fa_in_blk1) ;
	int facconn1(num_fac_per_el1) ;
		facconn1:elem_type = "NFACED" ;
	int ebepecnt1(num_el_in_blk1) ;
	char name_nod_var(num_nod_var, len_name) ;
	float vals_nod_var1(time_step, num_nodes) ;
	float vals_nod_var2(time_step, num_nodes) ;
	char name_elem_var(num_elem_var, len_name) ;
	float vals_elem_var1eb1(time_step, num_el_in_blk1) ;
data:
 time_whole = 0 ;
 eb_prop1 = 1 ;
 fa_prop1 = 1 ;
 coordx = 0, 1, 1, 0, 0, 1, 1, 0, 2, 2, 2, 2, 1.5, 1.5 ;
 coordy = 0, 0, 1, 1, 0, 0, 1, 1, 0, 1, 0, 1, 0, 1 ;
 coordz = 0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 1, 1, 1.5, 1.5 ;
 fbconn1 = 1, 4, 3, 2,  5, 6, 7, 8,  1, 2, 6, 5,  3, 4, 8, 7,  4, 1, 5, 8,  2, 3, 7, 6,
   2, 9, 11, 13, 6,  3, 7, 14, 12, 10,  2, 3, 10, 9,  9, 10, 12, 11,  11, 12, 14, 13,  13, 14, 7, 6 ;
 fbepecnt1 = 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4, 4 ;
 facconn1 = 1, 2, 3, 4, 5, 6,  6, 7, 8, 9, 10, 11, 12 ;
 ebepecnt1 = 6, 7 ;
 name_nod_var = "t", "u" ;
 vals_nod_var1 = 0, 1, 1, 0, 0, 1, 1, 0, 2, 2, 2, 2, 1.5, 1.5 ;
 vals_nod_var2 = 0, 1, 1, 0, 0, 1, 1, 0, 2, 2, 2, 2, 1.5, 1.5 ;
 name_elem_var = "t", "u" ;
 vals_elem_var1eb1 = 10, 20 ;
}
)";

TEST_F(Polyhedra, ExodusNfacedBlocks) {
  const std::string cdl = write("nfaced.cdl", kNfacedCdl), exo = (dir_ / "nfaced.e").string();
  const std::string command = std::string(UVR_NCGEN) + " -k nc3 -o '" + exo + "' '" + cdl + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const VolumeMesh mesh = VolumeMesh::load(exo);
  const CellCounts counts = mesh.cellCounts();
  EXPECT_EQ(counts.polyhedron, 2u);
  // The hexahedron: 6 pyramids. The prism: 2 pentagons (3 triangles each), 5 quads.
  EXPECT_EQ(counts.polyhedronPyramids, 11u);
  EXPECT_EQ(counts.polyhedronTets, 6u);
  EXPECT_EQ(counts.inverted, 0u);
  expectPositiveVolumes(mesh);
  const int cell = mesh.findField("cell:t"), point = mesh.findField("t");
  ASSERT_GE(cell, 0);
  ASSERT_GE(point, 0);
  EXPECT_EQ(mesh.field(point).centering, Centering::Point);
  std::vector<float> cellValues(mesh.fieldValues(cell).begin(), mesh.fieldValues(cell).end());
  EXPECT_EQ(std::count(cellValues.begin(), cellValues.end(), 10.f), 6);
  EXPECT_EQ(std::count(cellValues.begin(), cellValues.end(), 20.f), 11);
  // The point fields are x. The centres (the only points at y = 0.5): t takes the cell's value, u, whose
  // cells are NaN, the corners' average, x.
  const auto points = mesh.points();
  const auto t = mesh.fieldValues(point), u = mesh.fieldValues(mesh.findField("point:u"));
  int centres = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR(u[i], points[i].x, 1e-5f);
    if (points[i].y != 0.5f) {
      EXPECT_NEAR(t[i], points[i].x, 1e-5f);
      continue;
    }
    ++centres;
    EXPECT_EQ(t[i], points[i].x < 1.f ? 10.f : 20.f) << points[i].x;
  }
  EXPECT_EQ(centres, 2);
  // The shared face listed twice by the prism: three uses, refused.
  std::string three = kNfacedCdl;
  const std::string prismFaces = "6, 7, 8, 9, 10, 11, 12 ;";
  three.replace(three.find(prismFaces), prismFaces.size(), "6, 6, 8, 9, 10, 11, 12 ;");
  const std::string bad = write("thrice.cdl", three), badExo = (dir_ / "bad.e").string();
  ASSERT_EQ(std::system((std::string(UVR_NCGEN) + " -k nc3 -o '" + badExo + "' '" + bad + "'").c_str()), 0);
  try {
    VolumeMesh::load(badExo);
    ADD_FAILURE() << "a face of three polyhedra was accepted";
  } catch (const Error &e) {
    EXPECT_NE(std::string(e.what()).find("more than two polyhedra"), std::string::npos) << e.what();
  }
}
#endif

TEST(PolyhedronFaces, StreamMustFillItsSpan) {
  PolyhedronFaces faces;
  const std::vector<int64_t> tetra = {4, 3, 0, 1, 2, 3, 0, 3, 1, 3, 1, 3, 2, 3, 0, 2, 3};
  faces.appendStream(tetra, "s", "here");
  EXPECT_EQ(faces.polyhedronCount(), 1u);
  EXPECT_EQ(faces.faceOffsets.back(), 12);
  std::vector<int64_t> longer = tetra;
  longer.push_back(0);
  EXPECT_THROW(faces.appendStream(longer, "s", "here"), Error);
  EXPECT_THROW(faces.appendStream(std::span(tetra).first(10), "s", "here"), Error);
}

// Fields of one name at points and at cells.

/// Two tetrahedra with point field p = x and cell field p = 100 + cell, in the order `cellFirst` says.
TestGrid bothCentrings() {
  TestGrid grid;
  grid.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  grid.add(10, {0, 1, 2, 3});
  grid.add(10, {1, 2, 3, 4});
  grid.pointFields = {{"p", {0, 1, 0, 0, 1}}};
  grid.cellFields = {{"p", {100, 101}}};
  return grid;
}

/// The point and cell p of a mesh loaded from `path`: a plain name finds the point field, prefixes either.
void expectCentringChoice(const std::string &path) {
  SCOPED_TRACE(path);
  const VolumeMesh mesh = VolumeMesh::load(path);
  const int point = mesh.findField("point:p"), cell = mesh.findField("cell:p");
  ASSERT_GE(point, 0);
  ASSERT_GE(cell, 0);
  EXPECT_EQ(mesh.field(point).centering, Centering::Point);
  EXPECT_EQ(mesh.field(cell).centering, Centering::Cell);
  EXPECT_EQ(mesh.fieldRange(cell).min, 100.f);
  EXPECT_EQ(mesh.fieldRange(point).max, 1.f);
  EXPECT_EQ(mesh.findField("p"), point);
  EXPECT_EQ(mesh.chooseField("p"), point);
  EXPECT_EQ(mesh.chooseField("cell:p"), cell);
  EXPECT_EQ(mesh.findField("cell:q"), -1);
  try {
    mesh.chooseField("q");
    ADD_FAILURE() << "no error for a missing field";
  } catch (const Error &e) {
    // Both p, told apart, in the file's order.
    EXPECT_NE(std::string(e.what()).find("point:p"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cell:p"), std::string::npos) << e.what();
  }
}

TEST_F(Polyhedra, CentringPrefixesInEveryReader) {
  const TestGrid grid = bothCentrings();
  expectCentringChoice(write("both.vtu", vtuText(grid)));
  // Legacy files list cell data first here: the plain name still finds the point field.
  expectCentringChoice(write("both42.vtk", vtkText(grid, false, true)));
  expectCentringChoice(write("both51.vtk", vtkText(grid, true, false)));
  write("step.vtu", vtuText(grid));
  expectCentringChoice(write("both.pvd",
                             "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\"><Collection>"
                             "<DataSet timestep=\"0\" file=\"step.vtu\"/></Collection></VTKFile>\n"));
  // Gmsh: element data before node data.
  expectCentringChoice(write("both.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n"
                                         "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n"
                                         "$Elements\n2\n1 4 2 0 1 1 2 3 4\n2 4 2 0 1 2 3 4 5\n$EndElements\n"
                                         "$ElementData\n1\n\"p\"\n1\n0\n3\n0\n1\n2\n1 100\n2 101\n"
                                         "$EndElementData\n$NodeData\n1\n\"p\"\n1\n0\n3\n0\n1\n5\n"
                                         "1 0\n2 1\n3 0\n4 0\n5 1\n$EndNodeData\n"));
#if UVR_HAVE_NETCDF
  // Exodus: a nodal and an element variable of one name.
  std::ifstream cdlFile(std::string(UVR_TEST_DATA) + "/exodus/tets_nc4.cdl");
  std::string cdl((std::istreambuf_iterator<char>(cdlFile)), std::istreambuf_iterator<char>());
  const std::string from = "name_elem_var = \"id\"";
  ASSERT_NE(cdl.find(from), std::string::npos);
  cdl.replace(cdl.find(from), from.size(), "name_elem_var = \"u\"");
  const std::string cdlPath = write("both.cdl", cdl), exo = (dir_ / "both.e").string();
  const std::string command = std::string(UVR_NCGEN) + " -k nc4 -o '" + exo + "' '" + cdlPath + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const VolumeMesh mesh = VolumeMesh::load(exo);
  const int point = mesh.findField("u"), cell = mesh.findField("cell:u");
  ASSERT_GE(point, 0);
  ASSERT_GE(cell, 0);
  EXPECT_EQ(mesh.field(point).centering, Centering::Point);
  EXPECT_EQ(mesh.field(cell).centering, Centering::Cell);
  EXPECT_EQ(mesh.findField("point:u"), point);
  EXPECT_EQ(mesh.fieldRange(cell).max, 2.f);
#endif
  // umesh holds point fields only; the prefix finds them there too.
  const std::string umesh = (dir_ / "p.umesh").string();
  VolumeMesh both = VolumeMesh::load((dir_ / "both.vtu").string());
  const int pointP = both.findField("point:p");
  std::move(both).withFields({pointP}).save(umesh);
  const VolumeMesh fromUmesh = VolumeMesh::load(umesh);
  EXPECT_EQ(fromUmesh.findField("point:p"), 0);
  EXPECT_EQ(fromUmesh.findField("cell:p"), -1);
}

TEST(FieldNames, PrefixFallsBackToTheLiteralName) {
  Mesh mesh;
  mesh.fields.push_back({"cell:x", Centering::Point, {}});
  mesh.fields.push_back({"x", Centering::Cell, {}});
  mesh.fields.push_back({"x", Centering::Point, {}});
  EXPECT_EQ(mesh.findField("x"), 2);
  EXPECT_EQ(mesh.findField("cell:x"), 1);
  EXPECT_EQ(mesh.findField("point:x"), 2);
  mesh.fields.erase(mesh.fields.begin() + 1);
  EXPECT_EQ(mesh.findField("cell:x"), 0); // no cell field x: the field named "cell:x"
}

} // namespace
