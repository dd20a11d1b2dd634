#include "data_parallel.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <span>

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

struct Splitter {
  RegionTree &tree;
  std::vector<Vec3f> &centroids;

  int split(const Box3f &space, size_t begin, size_t end, int firstRegion, int count) {
    const int node = int(tree.nodes.size());
    tree.nodes.emplace_back();
    if (count == 1 || end - begin < 2) {
      // A region per rank even where the cells run out: the extra ones are empty.
      tree.nodes[size_t(node)].region = firstRegion;
      tree.regions[size_t(firstRegion)] = space;
      for (int r = 1; r < count; ++r) {
        tree.regions[size_t(firstRegion + r)] = Box3f{}; // empty: draws nothing
      }
      return node;
    }
    Box3f spread;
    for (size_t i = begin; i < end; ++i)
      spread.extend(centroids[i]);
    const Vec3f size = spread.upper - spread.lower;
    const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
    const int below = count / 2;
    const size_t middle = begin + (end - begin) * size_t(below) / size_t(count);
    std::nth_element(centroids.begin() + std::ptrdiff_t(begin), centroids.begin() + std::ptrdiff_t(middle),
                     centroids.begin() + std::ptrdiff_t(end),
                     [axis](const Vec3f &a, const Vec3f &b) { return a[axis] < b[axis]; });
    const float at = centroids[middle][axis];
    Box3f lower = space, upper = space;
    lower.upper[axis] = at;
    upper.lower[axis] = at;
    const int belowNode = split(lower, begin, middle, firstRegion, below);
    const int aboveNode = split(upper, middle, end, firstRegion + below, count - below);
    RegionTree::Node &n = tree.nodes[size_t(node)];
    n.axis = axis;
    n.split = at;
    n.below = belowNode;
    n.above = aboveNode;
    return node;
  }
};

void orderFrom(const RegionTree &tree, int node, Vec3f eye, std::vector<int> &order) {
  const RegionTree::Node &n = tree.nodes[size_t(node)];
  if (n.axis < 0) {
    order.push_back(n.region);
    return;
  }
  // The eye's side first: no ray from the eye crosses the plane back towards it.
  const bool eyeBelow = eye[n.axis] < n.split;
  orderFrom(tree, eyeBelow ? n.below : n.above, eye, order);
  orderFrom(tree, eyeBelow ? n.above : n.below, eye, order);
}

} // namespace

RegionTree splitIntoRegions(const VolumeMesh &mesh, int count) {
  const std::span<const Vec3f> points = mesh.points();
  std::vector<Vec3f> centroids;
  centroids.reserve(mesh.cellCount());
  forEachCell(mesh, [&](uint64_t, CellType, std::span<const uint32_t> corners) {
    Vec3f sum{0.f, 0.f, 0.f};
    for (const uint32_t v : corners)
      sum = sum + points[v];
    centroids.push_back(sum * (1.f / float(corners.size())));
  });
  // Far past the bounds: the outer faces of the outer regions never cut a ray's part inside the mesh.
  const Box3f bounds = mesh.bounds();
  const float reach = length(bounds.upper - bounds.lower) + 1.f;
  Box3f space = bounds;
  space.lower = space.lower - Vec3f{reach, reach, reach};
  space.upper = space.upper + Vec3f{reach, reach, reach};
  RegionTree tree;
  tree.regions.resize(size_t(count));
  Splitter{tree, centroids}.split(space, 0, centroids.size(), 0, count);
  return tree;
}

VolumeMesh meshPiece(const VolumeMesh &mesh, int fieldIndex, const Box3f &region) {
  const std::span<const Vec3f> points = mesh.points();
  const FieldInfo field = mesh.field(fieldIndex);
  const std::span<const float> values = mesh.fieldValues(fieldIndex);
  std::vector<int64_t> offsets{0}, connectivity;
  std::vector<uint8_t> types;
  std::vector<float> cellValues;
  forEachCell(mesh, [&](uint64_t cell, CellType type, std::span<const uint32_t> corners) {
    if (region.empty() || !touches(cornerBounds(points, corners), region))
      return;
    for (const uint32_t v : corners)
      connectivity.push_back(int64_t(v));
    offsets.push_back(int64_t(connectivity.size()));
    types.push_back(uint8_t(type));
    if (field.centering == Centering::Cell)
      cellValues.push_back(values[cell]);
  });
  MeshArrays arrays;
  arrays.points = ArrayView(std::span<const float>(&points.data()->x, 3 * points.size()), 3);
  arrays.offsets = offsets;
  arrays.connectivity = connectivity;
  arrays.types = types;
  arrays.fields.push_back(
      {field.name, field.centering,
       ArrayView(field.centering == Centering::Cell ? std::span<const float>(cellValues) : values)});
  return VolumeMesh::fromArrays(arrays, mesh.source());
}

std::vector<int> visibilityOrder(const RegionTree &tree, Vec3f eye) {
  std::vector<int> order;
  orderFrom(tree, 0, eye, order);
  return order;
}

} // namespace uvr
