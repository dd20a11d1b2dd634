#include "mesh/mesh.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>

namespace uvr {
namespace {

// Spreads the low 21 bits of `v` so that two zero bits follow each.
uint64_t spreadBits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

struct MortonQuantizer {
  Vec3f lower, scale;

  explicit MortonQuantizer(const Box3f &box) : lower(box.lower) {
    const Vec3f extent = box.upper - box.lower;
    constexpr float kCells = float(1 << 21) - 1.f;
    scale = {extent.x > 0.f ? kCells / extent.x : 0.f, extent.y > 0.f ? kCells / extent.y : 0.f,
             extent.z > 0.f ? kCells / extent.z : 0.f};
  }
  uint64_t code(Vec3f p) const {
    const Vec3f d = p - lower;
    const Vec3f q{d.x * scale.x, d.y * scale.y, d.z * scale.z};
    return spreadBits(uint64_t(clampf(q.x, 0.f, 2097151.f))) |
           spreadBits(uint64_t(clampf(q.y, 0.f, 2097151.f))) << 1 |
           spreadBits(uint64_t(clampf(q.z, 0.f, 2097151.f))) << 2;
  }
};

struct Keyed {
  uint64_t code;
  uint32_t index;
  bool operator<(const Keyed &other) const {
    return code < other.code || (code == other.code && index < other.index);
  }
};

/// Sorts the cells of one type array by the Morton code of their centroids; returns the new order
/// (order[newIndex] = oldIndex), or an empty vector when the cells are already in that order.
std::vector<uint32_t> mortonOrder(const std::vector<uint32_t> &cells, int corners,
                                  const std::vector<Vec3f> &points, const MortonQuantizer &quantizer) {
  const size_t count = cells.size() / size_t(corners);
  std::vector<Keyed> keys(count);
  tbb::parallel_for(size_t(0), count, [&](size_t c) {
    Vec3f sum{0.f, 0.f, 0.f};
    for (int i = 0; i < corners; ++i)
      sum = sum + points[cells[c * size_t(corners) + size_t(i)]];
    keys[c] = {quantizer.code(sum * (1.f / float(corners))), uint32_t(c)};
  });
  if (std::is_sorted(keys.begin(), keys.end()))
    return {};
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<uint32_t> order(count);
  tbb::parallel_for(size_t(0), count, [&](size_t i) { order[i] = keys[i].index; });
  return order;
}

template <typename T>
void permute(std::vector<T> &values, const std::vector<uint32_t> &order, size_t stride, size_t offset = 0) {
  std::vector<T> copy(values.begin() + std::ptrdiff_t(offset * stride),
                      values.begin() + std::ptrdiff_t((offset + order.size()) * stride));
  tbb::parallel_for(size_t(0), order.size(), [&](size_t i) {
    std::copy_n(copy.begin() + std::ptrdiff_t(size_t(order[i]) * stride), stride,
                values.begin() + std::ptrdiff_t((offset + i) * stride));
  });
}

} // namespace

void orderSpatially(Mesh &mesh) {
  if (mesh.points.empty())
    return;
  const MortonQuantizer quantizer(mesh.bounds());

  // Cells: each type array on its own, so that the type order (and thus cell indices' meaning) is kept.
  struct TypeArray {
    std::vector<uint32_t> *cells;
    int corners;
  };
  const TypeArray arrays[] = {{&mesh.tets, 4}, {&mesh.pyramids, 5}, {&mesh.wedges, 6}, {&mesh.hexes, 8}};
  size_t firstCell = 0;
  for (const TypeArray &array : arrays) {
    const size_t count = array.cells->size() / size_t(array.corners);
    const std::vector<uint32_t> order = mortonOrder(*array.cells, array.corners, mesh.points, quantizer);
    if (!order.empty()) {
      permute(*array.cells, order, size_t(array.corners));
      for (ScalarField &field : mesh.fields)
        if (field.centering == Centering::Cell)
          permute(field.values, order, 1, firstCell);
    }
    firstCell += count;
  }

  // Points: numbered by first use in the new cell order, so that a cell's corners lie close in memory.
  constexpr uint32_t kUnused = 0xffffffffu;
  std::vector<uint32_t> newIndex(mesh.points.size(), kUnused);
  uint32_t next = 0;
  for (const TypeArray &array : arrays)
    for (uint32_t &v : *array.cells) {
      if (newIndex[v] == kUnused)
        newIndex[v] = next++;
      v = newIndex[v];
    }
  for (uint32_t &index : newIndex) // points no cell uses keep their relative order at the end
    if (index == kUnused)
      index = next++;
  std::vector<uint32_t> order(mesh.points.size());
  for (size_t i = 0; i < order.size(); ++i)
    order[newIndex[i]] = uint32_t(i);
  permute(mesh.points, order, 1);
  for (ScalarField &field : mesh.fields)
    if (field.centering == Centering::Point)
      permute(field.values, order, 1);
}

} // namespace uvr
