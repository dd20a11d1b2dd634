#include "data_parallel.h"

#include <uvr/error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
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

/// The cells for which `keep(cornerBox)` holds, with fields `fields`, and the points they use (in their
/// order in `mesh`); which are kept is decided on all cores, block by block.
template <class Keep>
VolumeMesh selectCells(const VolumeMesh &mesh, const std::vector<int> &fields, const Keep &keep) {
  const std::span<const Vec3f> points = mesh.points();
  std::vector<uint8_t> kept(mesh.cellCount());
  uint64_t first = 0;
  for (const CellType type : kCellTypes) {
    const size_t n = size_t(cornerCount(type));
    const std::span<const uint32_t> corners = mesh.cells(type);
    const uint64_t count = corners.size() / n;
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, uint64_t(1) << 15),
                      [&](const tbb::blocked_range<uint64_t> &r) {
                        for (uint64_t c = r.begin(); c < r.end(); ++c)
                          kept[first + c] = keep(cornerBounds(points, corners.subspan(c * n, n)));
                      });
    first += count;
  }
  return mesh.selectCells(kept, fields);
}

std::vector<int> allFields(const VolumeMesh &mesh) {
  std::vector<int> fields(size_t(mesh.fieldCount()));
  for (int f = 0; f < mesh.fieldCount(); ++f)
    fields[size_t(f)] = f;
  return fields;
}

/// Whether `region` holds the box centre `c`, taken half-open as the partitions' tree assigns cells.
bool owns(const Box3f &region, Vec3f c) {
  return region.lower.x <= c.x && c.x < region.upper.x && region.lower.y <= c.y && c.y < region.upper.y &&
         region.lower.z <= c.z && c.z < region.upper.z;
}

} // namespace

namespace {

int addRegions(MeshRegions &split, const std::vector<Box3f> &boxes, int first, int count) {
  const int index = int(split.nodes.size());
  split.nodes.emplace_back();
  if (count == 1) {
    split.nodes[size_t(index)].region = first;
    return index;
  }
  // As splitIntoRegions: count / 2 regions below the split.
  const int below = count / 2;
  Box3f low, high;
  for (int i = 0; i < count; ++i)
    (i < below ? low : high).extend(boxes[size_t(first + i)]);
  int axis = 0;
  while (axis < 3 && low.upper[axis] != high.lower[axis])
    ++axis;
  if (axis == 3)
    throw Error("the pieces' regions are not the regions of a KD split");
  const int lower = addRegions(split, boxes, first, below);
  const int upper = addRegions(split, boxes, first + below, count - below);
  split.nodes[size_t(index)] = {axis, low.upper[axis], lower, upper, -1};
  return index;
}

} // namespace

MeshRegions regionsOfPieces(const std::vector<Box3f> &pieceRegions, int count) {
  const size_t each = pieceRegions.size() / size_t(count);
  MeshRegions split;
  for (int r = 0; r < count; ++r) {
    Box3f box;
    for (size_t i = 0; i < each; ++i)
      box.extend(pieceRegions[size_t(r) * each + i]);
    split.regions.push_back(box);
  }
  addRegions(split, split.regions, 0, count);
  return split;
}

VolumeMesh meshPiece(const VolumeMesh &mesh, int fieldIndex, const Box3f &region) {
  return selectCells(mesh, {fieldIndex},
                     [&](const Box3f &box) { return !region.empty() && touches(box, region); });
}

VolumeMesh ownedCells(const VolumeMesh &mesh, const Box3f &region) {
  return selectCells(mesh, allFields(mesh), [&](const Box3f &box) { return owns(region, box.center()); });
}

VolumeMesh ghostCells(const VolumeMesh &mesh, const Box3f &region) {
  return selectCells(mesh, allFields(mesh), [&](const Box3f &box) {
    return !region.empty() && touches(box, region) && !owns(region, box.center());
  });
}

VolumeMesh ghostCellsOutside(const VolumeMesh &ghosts, const std::vector<Box3f> &owned,
                             const std::vector<Box3f> &earlier) {
  return selectCells(ghosts, allFields(ghosts), [&](const Box3f &box) {
    for (const Box3f &region : owned)
      if (owns(region, box.center()))
        return false;
    for (const Box3f &region : earlier)
      if (touches(box, region))
        return false;
    return true;
  });
}

VolumeMesh mergeMeshes(const std::vector<VolumeMesh> &parts, const std::string &source) {
  // A point of a later part at the coordinates of an earlier part's point is that point: the pieces of one
  // mesh share the points on their common faces, and the cells across them stay neighbours.
  struct Key {
    uint32_t x, y, z;
    bool operator==(const Key &) const = default;
  };
  struct Hash {
    size_t operator()(const Key &k) const {
      return size_t(k.x) * 0x9E3779B97F4A7C15ull ^ size_t(k.y) * 0xC2B2AE3D27D4EB4Full ^ size_t(k.z);
    }
  };
  const auto keyOf = [](Vec3f p) {
    return Key{std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y), std::bit_cast<uint32_t>(p.z)};
  };
  std::unordered_map<Key, uint32_t, Hash> earlier;
  std::vector<float> points;
  std::vector<int64_t> offsets{0}, connectivity;
  std::vector<uint8_t> types;
  const int fieldCount = parts.empty() ? 0 : parts[0].fieldCount();
  std::vector<std::vector<float>> values(static_cast<size_t>(fieldCount));
  for (const VolumeMesh &part : parts) {
    if (part.fieldCount() != fieldCount)
      throw Error(part.source(), "", "the pieces hold different fields");
    const std::span<const Vec3f> partPoints = part.points();
    std::vector<std::span<const float>> pointValues(static_cast<size_t>(fieldCount)),
        cellValues(static_cast<size_t>(fieldCount));
    for (int f = 0; f < fieldCount; ++f)
      (part.field(f).centering == Centering::Point ? pointValues : cellValues)[size_t(f)] =
          part.fieldValues(f);
    std::vector<uint32_t> index(partPoints.size());
    std::vector<std::pair<Key, uint32_t>> added;
    for (size_t v = 0; v < partPoints.size(); ++v) {
      const Key key = keyOf(partPoints[v]);
      const auto found = earlier.find(key);
      if (found != earlier.end()) {
        index[v] = found->second;
        continue;
      }
      index[v] = uint32_t(points.size() / 3);
      points.insert(points.end(), {partPoints[v].x, partPoints[v].y, partPoints[v].z});
      added.emplace_back(key, index[v]);
      for (size_t f = 0; f < pointValues.size(); ++f)
        if (!pointValues[f].empty())
          values[f].push_back(pointValues[f][v]);
    }
    earlier.insert(added.begin(), added.end());
    forEachCell(part, [&](uint64_t cell, CellType type, std::span<const uint32_t> corners) {
      for (const uint32_t v : corners)
        connectivity.push_back(int64_t(index[v]));
      offsets.push_back(int64_t(connectivity.size()));
      types.push_back(uint8_t(type));
      for (size_t f = 0; f < cellValues.size(); ++f)
        if (!cellValues[f].empty())
          values[f].push_back(cellValues[f][cell]);
    });
  }
  MeshArrays arrays;
  arrays.points = ArrayView(std::span<const float>(points), 3);
  arrays.offsets = offsets;
  arrays.connectivity = connectivity;
  arrays.types = types;
  for (int f = 0; f < fieldCount; ++f) {
    const FieldInfo field = parts[0].field(f);
    arrays.fields.push_back(
        {field.name, field.centering, ArrayView(std::span<const float>(values[size_t(f)]))});
  }
  return VolumeMesh::fromArrays(arrays, source);
}

} // namespace uvr
