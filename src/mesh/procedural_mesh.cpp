#include "mesh/procedural_mesh.h"

#include <algorithm>
#include <random>

namespace uvr {

namespace {

/// Appends a cell, wound as VTK expects whatever the order given.
void addCell(UnstructuredGrid &grid, CellType type, std::initializer_list<uint32_t> ids) {
  uint32_t v[8];
  std::copy(ids.begin(), ids.end(), v);
  orientCell(type, v, grid.points);
  for (size_t i = 0; i < ids.size(); ++i)
    grid.connectivity.push_back(v[i]);
  grid.offsets.push_back(int64_t(grid.connectivity.size()));
  grid.types.push_back(uint8_t(type));
}

/// The point field "f" and the cell field "f_cell" of makeBoxGrid.
void addFields(UnstructuredGrid &grid, const std::function<float(Vec3f)> &field) {
  ScalarField pointField{"f", Centering::Point, {}};
  for (const Vec3f &p : grid.points)
    pointField.values.push_back(field(p));
  ScalarField cellField{"f_cell", Centering::Cell, {}};
  for (size_t cell = 0; cell + 1 < grid.offsets.size(); ++cell) {
    Vec3f centroid{};
    const auto first = size_t(grid.offsets[cell]), last = size_t(grid.offsets[cell + 1]);
    for (size_t v = first; v < last; ++v)
      centroid = centroid + grid.points[size_t(grid.connectivity[v])];
    cellField.values.push_back(field(centroid / float(last - first)));
  }
  grid.fields = {std::move(pointField), std::move(cellField)};
}

/// makeBoxGrid's cells and points, without its fields.
UnstructuredGrid boxLattice(CellType type, int n, const Box3f &box, float jitter, unsigned seed) {
  UnstructuredGrid grid;
  grid.offsets.push_back(0);
  const int m = n + 1;
  const Vec3f step = box.size() / float(n);
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> offset(-jitter, jitter);
  auto index = [m](int i, int j, int k) { return uint32_t((k * m + j) * m + i); };
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        Vec3f p = box.lower + Vec3f{float(i) * step.x, float(j) * step.y, float(k) * step.z};
        const bool interior = i > 0 && j > 0 && k > 0 && i < n && j < n && k < n;
        if (interior && jitter > 0.f)
          p = p + Vec3f{offset(random) * step.x, offset(random) * step.y, offset(random) * step.z};
        grid.points.push_back(p);
      }

  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        // Corner c of the cube: bit 0 = +x, bit 1 = +y, bit 2 = +z.
        uint32_t c[8];
        for (int b = 0; b < 8; ++b)
          c[b] = index(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        switch (type) {
        case CellType::Tetra: {
          // Kuhn's six tetrahedra along the main diagonal; neighbouring cubes cut their shared faces alike.
          const int paths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
          for (const auto &path : paths)
            addCell(grid, type, {c[0], c[path[0]], c[path[1]], c[7]});
          break;
        }
        case CellType::Hexahedron:
          addCell(grid, type, {c[0], c[1], c[3], c[2], c[4], c[5], c[7], c[6]});
          break;
        case CellType::Wedge:
          addCell(grid, type, {c[0], c[3], c[1], c[4], c[7], c[5]});
          addCell(grid, type, {c[0], c[2], c[3], c[4], c[6], c[7]});
          break;
        case CellType::Pyramid: {
          Vec3f centre{};
          for (uint32_t id : c)
            centre = centre + grid.points[id] * 0.125f;
          const auto apex = uint32_t(grid.points.size());
          grid.points.push_back(centre);
          // Each face of the cube is the base of one pyramid.
          addCell(grid, type, {c[0], c[2], c[3], c[1], apex}); // -z
          addCell(grid, type, {c[4], c[5], c[7], c[6], apex}); // +z
          addCell(grid, type, {c[0], c[1], c[5], c[4], apex}); // -y
          addCell(grid, type, {c[2], c[6], c[7], c[3], apex}); // +y
          addCell(grid, type, {c[0], c[4], c[6], c[2], apex}); // -x
          addCell(grid, type, {c[1], c[3], c[7], c[5], apex}); // +x
          break;
        }
        }
      }
  return grid;
}

} // namespace

UnstructuredGrid makeBoxGrid(CellType type, int n, const Box3f &box, const std::function<float(Vec3f)> &field,
                             float jitter, unsigned seed) {
  UnstructuredGrid grid = boxLattice(type, n, box, jitter, seed);
  addFields(grid, field);
  return grid;
}

UnstructuredGrid makePyramidsAndTets(int n, const Box3f &box, const std::function<float(Vec3f)> &field,
                                     float jitter, unsigned seed) {
  const UnstructuredGrid pyramids = boxLattice(CellType::Pyramid, n, box, jitter, seed);
  UnstructuredGrid grid;
  grid.points = pyramids.points;
  grid.offsets.push_back(0);
  for (size_t c = 0; c + 1 < pyramids.offsets.size(); ++c) {
    const int64_t *v = pyramids.connectivity.data() + pyramids.offsets[c]; // base 0-3, apex 4
    const auto id = [&](int i) { return uint32_t(v[i]); };
    bool onSide = false;
    for (int axis = 0; axis < 3; ++axis) {
      const float side = grid.points[id(0)][axis];
      bool same = side == box.lower[axis] || side == box.upper[axis];
      for (int i = 1; i < 4; ++i)
        same = same && grid.points[id(i)][axis] == side;
      onSide = onSide || same;
    }
    if (onSide) {
      addCell(grid, CellType::Tetra, {id(0), id(1), id(2), id(4)});
      addCell(grid, CellType::Tetra, {id(0), id(2), id(3), id(4)});
    } else {
      addCell(grid, CellType::Pyramid, {id(0), id(1), id(2), id(3), id(4)});
    }
  }
  addFields(grid, field);
  return grid;
}

UnstructuredGrid keepCells(const UnstructuredGrid &grid, const std::function<bool(Vec3f)> &keep) {
  UnstructuredGrid kept = grid;
  kept.offsets = {0};
  kept.connectivity.clear();
  kept.types.clear();
  for (size_t c = 0; c + 1 < grid.offsets.size(); ++c) {
    Vec3f centre{0.f, 0.f, 0.f};
    const int64_t first = grid.offsets[c], last = grid.offsets[c + 1];
    for (int64_t i = first; i < last; ++i)
      centre = centre + grid.points[size_t(grid.connectivity[size_t(i)])] * (1.f / float(last - first));
    if (!keep(centre))
      continue;
    kept.connectivity.insert(kept.connectivity.end(), grid.connectivity.begin() + first,
                             grid.connectivity.begin() + last);
    kept.offsets.push_back(int64_t(kept.connectivity.size()));
    kept.types.push_back(grid.types[c]);
  }
  kept.fields.resize(1);
  return kept;
}

} // namespace uvr
