#include "data_parallel.h"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace uvr {

namespace {

constexpr CellType kCellTypes[] = {CellType::Tetra, CellType::Pyramid, CellType::Wedge, CellType::Hexahedron};

int cornerCount(CellType type) {
  switch (type) {
  case CellType::Tetra:
    return 4;
  case CellType::Pyramid:
    return 5;
  case CellType::Wedge:
    return 6;
  case CellType::Hexahedron:
    return 8;
  }
  return 0;
}

/// Calls visit(cellIndex, type, corners) for every cell in the mesh's order (tets, pyramids, wedges, hexes).
template <class Visit> void forEachCell(const VolumeMesh &mesh, Visit &&visit) {
  uint64_t index = 0;
  for (const CellType type : kCellTypes) {
    const int n = cornerCount(type);
    const std::span<const uint32_t> corners = mesh.cells(type);
    for (size_t c = 0; c + size_t(n) <= corners.size(); c += size_t(n))
      visit(index++, type, corners.subspan(c, size_t(n)));
  }
}

Box3f cornerBounds(std::span<const Vec3f> points, std::span<const uint32_t> corners) {
  Box3f box;
  for (const uint32_t v : corners)
    box.extend(points[v]);
  return box;
}

bool touches(const Box3f &a, const Box3f &b) {
  return a.lower.x <= b.upper.x && b.lower.x <= a.upper.x && a.lower.y <= b.upper.y &&
         b.lower.y <= a.upper.y && a.lower.z <= b.upper.z && b.lower.z <= a.upper.z;
}

} // namespace

namespace {

/// The cells for which `keep(cornerBox)` holds, with fields `fields`.
template <class Keep>
VolumeMesh selectCells(const VolumeMesh &mesh, const std::vector<int> &fields, const Keep &keep) {
  const std::span<const Vec3f> points = mesh.points();
  std::vector<int64_t> offsets{0}, connectivity;
  std::vector<uint8_t> types;
  std::vector<std::vector<float>> cellValues(fields.size());
  forEachCell(mesh, [&](uint64_t cell, CellType type, std::span<const uint32_t> corners) {
    if (!keep(cornerBounds(points, corners)))
      return;
    for (const uint32_t v : corners)
      connectivity.push_back(int64_t(v));
    offsets.push_back(int64_t(connectivity.size()));
    types.push_back(uint8_t(type));
    for (size_t f = 0; f < fields.size(); ++f)
      if (mesh.field(fields[f]).centering == Centering::Cell)
        cellValues[f].push_back(mesh.fieldValues(fields[f])[cell]);
  });
  MeshArrays arrays;
  arrays.points = ArrayView(std::span<const float>(&points.data()->x, 3 * points.size()), 3);
  arrays.offsets = offsets;
  arrays.connectivity = connectivity;
  arrays.types = types;
  for (size_t f = 0; f < fields.size(); ++f) {
    const FieldInfo field = mesh.field(fields[f]);
    const bool perCell = field.centering == Centering::Cell;
    arrays.fields.push_back(
        {field.name, field.centering,
         ArrayView(perCell ? std::span<const float>(cellValues[f]) : mesh.fieldValues(fields[f]))});
  }
  return VolumeMesh::fromArrays(arrays, mesh.source());
}

} // namespace

VolumeMesh meshPiece(const VolumeMesh &mesh, int fieldIndex, const Box3f &region) {
  return selectCells(mesh, {fieldIndex},
                     [&](const Box3f &box) { return !region.empty() && touches(box, region); });
}

VolumeMesh ownedCells(const VolumeMesh &mesh, const Box3f &region) {
  std::vector<int> fields(size_t(mesh.fieldCount()));
  for (int f = 0; f < mesh.fieldCount(); ++f)
    fields[size_t(f)] = f;
  return selectCells(mesh, fields, [&](const Box3f &box) {
    const Vec3f c = box.center();
    return region.lower.x <= c.x && c.x < region.upper.x && region.lower.y <= c.y && c.y < region.upper.y &&
           region.lower.z <= c.z && c.z < region.upper.z;
  });
}

} // namespace uvr
