#include "mesh/cell_neighbors.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <tuple>

namespace uvr {

namespace {

/// A face as its sorted corner points (a triangle's fourth is kNoCell), with the cell and face it bounds.
struct FaceKey {
  std::array<uint32_t, 4> points;
  uint32_t cell;
  uint8_t face;

  bool operator<(const FaceKey &other) const {
    return std::tie(points, cell, face) < std::tie(other.points, other.cell, other.face);
  }
};

} // namespace

uint64_t cellAdjacencyBytes(const MeshView &mesh) {
  const uint64_t otherCells = mesh.cellCount() - mesh.tetCount;
  return kMaxCellFaces * (otherCells * (sizeof(uint32_t) + sizeof(FaceKey)) +
                          (mesh.pyramidCount + mesh.wedgeCount) * sizeof(Vec4f));
}

std::vector<uint32_t> buildCellNeighbors(const Mesh &cells) {
  const MeshView mesh = makeMeshView(cells, -1);
  const uint64_t otherCells = mesh.cellCount() - mesh.tetCount;
  if (otherCells == 0)
    return {};
  // Every face of the other cells, and the tet faces among their points, keyed by its points: a face two
  // cells share sorts into two neighbouring entries.
  const uint64_t otherKeys = kMaxCellFaces * otherCells;
  std::vector<FaceKey> keys(otherKeys, FaceKey{{kNoCell, kNoCell, kNoCell, kNoCell}, kNoCell, 0});
  std::vector<uint8_t> onOtherCell(mesh.tetCount > 0 ? cells.points.size() : 0, 0);
  tbb::parallel_for(mesh.tetCount, mesh.cellCount(), [&](uint64_t cell) {
    int n;
    const uint32_t *v = cellCorners(mesh, cell, n);
    const CellFaces faces = cellFaces(cellType(mesh, cell));
    for (int f = 0; f < faces.count; ++f) {
      FaceKey &key = keys[kMaxCellFaces * (cell - mesh.tetCount) + uint64_t(f)];
      for (int i = 0; i < 4; ++i)
        key.points[size_t(i)] = faces.corners[f][i] < 0 ? kNoCell : v[faces.corners[f][i]];
      std::sort(key.points.begin(), key.points.end());
      key.cell = uint32_t(cell);
      key.face = uint8_t(f);
    }
    if (!onOtherCell.empty())
      for (int i = 0; i < n; ++i)
        std::atomic_ref<uint8_t>(onOtherCell[v[i]]).store(1, std::memory_order_relaxed);
  });
  for (uint64_t tet = 0; tet < mesh.tetCount; ++tet) {
    const uint32_t *v = mesh.tets + 4 * tet;
    for (int f = 0; f < 4; ++f) { // face f is the one opposite corner f, as in tetFaceCorners
      const uint32_t a = v[(f + 1) & 3], b = v[(f + 2) & 3], c = v[(f + 3) & 3];
      if (onOtherCell[a] && onOtherCell[b] && onOtherCell[c]) {
        FaceKey key{{a, b, c, kNoCell}, uint32_t(tet), uint8_t(f)};
        std::sort(key.points.begin(), key.points.end());
        keys.push_back(key);
      }
    }
  }
  const uint64_t keyCount = keys.size();
  tbb::parallel_sort(keys.begin(), keys.end());

  std::vector<uint32_t> neighbors(kMaxCellFaces * otherCells, kNoCell);
  auto link = [&](const FaceKey &from, const FaceKey &to) {
    if (from.cell >= mesh.tetCount)
      neighbors[kMaxCellFaces * (from.cell - mesh.tetCount) + from.face] = to.cell;
  };
  tbb::parallel_for(uint64_t(1), keyCount, [&](uint64_t i) {
    const FaceKey &a = keys[i - 1], &b = keys[i];
    if (a.cell == kNoCell || a.points != b.points || a.cell == b.cell)
      return;
    // Only a pair: a face shared by more cells (a non-manifold mesh) links none of them.
    if ((i >= 2 && keys[i - 2].points == a.points) || (i + 1 < keyCount && keys[i + 1].points == a.points))
      return;
    link(a, b);
    link(b, a);
  });
  return neighbors;
}

namespace {

/// Calls `visit(tet, i, cell)` for each face i of a tet (the one opposite its corner i) that `cellNeighbors`
/// says another cell `cell` shares, for other cells [begin, end) (counted from the first cell that is not a
/// tet).
template <class Visit>
void forEachTetFaceOfOtherCells(const MeshView &mesh, const std::vector<uint32_t> &cellNeighbors,
                                uint64_t begin, uint64_t end, Visit &&visit) {
  for (uint64_t other = begin; other < end; ++other) {
    const uint64_t cell = mesh.tetCount + other;
    int count;
    const uint32_t *v = cellCorners(mesh, cell, count);
    const CellFaces faces = cellFaces(cellType(mesh, cell));
    for (int f = 0; f < faces.count; ++f) {
      const uint32_t across = cellNeighbors[kMaxCellFaces * other + uint64_t(f)];
      if (across >= mesh.tetCount)
        continue;
      // The tet's face is the one opposite its corner that the face does not hold.
      const uint32_t *tet = mesh.tets + 4 * uint64_t(across);
      for (int corner = 0; corner < 4; ++corner) {
        bool held = false;
        for (int k = 0; k < 4 && faces.corners[f][k] >= 0; ++k)
          held = held || v[faces.corners[f][k]] == tet[corner];
        if (!held)
          visit(across, corner, uint32_t(cell));
      }
    }
  }
}

} // namespace

void linkTetsToOtherCells(const MeshView &mesh, const std::vector<uint32_t> &cellNeighbors,
                          std::span<uint32_t> tetNeighbors) {
  const uint64_t otherCells = mesh.cellCount() - mesh.tetCount;
  if (otherCells == 0 || cellNeighbors.size() != kMaxCellFaces * otherCells ||
      tetNeighbors.size() != 4 * mesh.tetCount)
    return;
  // A tet face has one cell across, so each entry is written by one cell at most.
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, otherCells), [&](const tbb::blocked_range<uint64_t> &r) {
    forEachTetFaceOfOtherCells(
        mesh, cellNeighbors, r.begin(), r.end(),
        [&](uint32_t tet, int i, uint32_t cell) { tetNeighbors[4 * uint64_t(tet) + uint64_t(i)] = cell; });
  });
}

std::vector<uint32_t> listBoundaryCellFaces(const MeshView &mesh, const uint32_t *tetNeighbors,
                                            const std::vector<uint32_t> &cellNeighbors) {
  const uint64_t otherCells = mesh.cellCount() - mesh.tetCount;
  if (otherCells == 0 || mesh.cellCount() > (uint64_t(1) << 29) || (mesh.tetCount > 0 && !tetNeighbors) ||
      cellNeighbors.size() != kMaxCellFaces * otherCells)
    return {};
  // A tet face that another cell shares has no tet across: a bit per face marks those the other cells name
  // (`tetNeighbors` may not, see linkTetsToOtherCells).
  std::vector<uint8_t> sharedTetFaces(mesh.tetCount, 0);
  forEachTetFaceOfOtherCells(mesh, cellNeighbors, 0, otherCells,
                             [&](uint32_t tet, int i, uint32_t) { sharedTetFaces[tet] |= uint8_t(1u << i); });
  std::vector<uint32_t> faces;
  const uint32_t bits = boundaryFaceBits(mesh);
  for (uint64_t tet = 0; tet < mesh.tetCount; ++tet)
    for (uint32_t i = 0; i < 4; ++i)
      if (tetNeighbors[4 * tet + i] == kNoCell && !((sharedTetFaces[tet] >> i) & 1u))
        faces.push_back(uint32_t(tet << bits) + i);
  for (uint64_t other = 0; other < otherCells; ++other) {
    const uint64_t cell = mesh.tetCount + other;
    const int count = cellFaces(cellType(mesh, cell)).count;
    for (int f = 0; f < count; ++f)
      if (cellNeighbors[kMaxCellFaces * other + uint64_t(f)] == kNoCell)
        faces.push_back(uint32_t(cell << bits) + uint32_t(f));
  }
  return faces;
}

std::vector<Vec4f> buildCellFacePlanes(const MeshView &mesh) {
  const uint64_t firstHex = mesh.tetCount + mesh.pyramidCount + mesh.wedgeCount;
  std::vector<Vec4f> planes(kMaxCellFaces * (firstHex - mesh.tetCount), Vec4f{0.f, 0.f, 0.f, -INFINITY});
  tbb::parallel_for(mesh.tetCount, firstHex, [&](uint64_t cell) {
    int n;
    const uint32_t *v = cellCorners(mesh, cell, n);
    const CellFaces faces = cellFaces(cellType(mesh, cell));
    Vec3f centre{};
    for (int i = 0; i < n; ++i)
      centre = centre + mesh.points[v[i]];
    centre = centre * (1.f / float(n));
    const float size = length(mesh.points[v[0]] - centre);
    for (int f = 0; f < faces.count; ++f) {
      const int8_t *c = faces.corners[f];
      const Vec3f a = mesh.points[v[c[0]]], b = mesh.points[v[c[1]]], d = mesh.points[v[c[2]]];
      Vec3f normal, middle;
      if (c[3] < 0) {
        normal = cross(b - a, d - a);
        middle = (a + b + d) * (1.f / 3.f);
      } else {
        const Vec3f e = mesh.points[v[c[3]]];
        normal = cross(d - a, e - b);
        middle = (a + b + d + e) * 0.25f;
      }
      const float norm = length(normal) * size;
      if (!(norm > 0.f))
        continue; // a collapsed face: never the way out
      if (dot(normal, middle - centre) < 0.f)
        normal = normal * -1.f;
      normal = normal * (1.f / norm);
      planes[kMaxCellFaces * (cell - mesh.tetCount) + uint64_t(f)] = {normal.x, normal.y, normal.z,
                                                                      -dot(normal, middle)};
    }
  });
  return planes;
}

} // namespace uvr
