// The steps of orderSpatially, for buildMesh to use one by one: it computes each cell's Morton key in the
// pass that writes and winds the cell, while the cell's points are still in cache.
#pragma once

#include "core/buffer.h"
#include "mesh/mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <array>
#include <span>

namespace uvr {

/// Keys that order cells along a Morton curve through their centroids: a 30-bit code (a 1024³ grid over the
/// mesh bounds; fine enough to order a billion cells for locality) beside the cell's 32-bit index.
class CellKeys {
public:
  explicit CellKeys(const Box3f &bounds) : lower_(bounds.lower) {
    const Vec3f extent = bounds.upper - bounds.lower;
    scale_ = {extent.x > 0.f ? kLast / extent.x : 0.f, extent.y > 0.f ? kLast / extent.y : 0.f,
              extent.z > 0.f ? kLast / extent.z : 0.f};
  }

  /// The key of the cell with corners v[0, corners) at index `index` of its type array.
  uint64_t key(const uint32_t *v, int corners, std::span<const Vec3f> points, uint64_t index) const {
    Vec3f sum{0.f, 0.f, 0.f};
    for (int i = 0; i < corners; ++i)
      sum = sum + points[v[i]];
    return uint64_t(code(sum * (1.f / float(corners)))) << 32 | index;
  }

  static constexpr int kBits = 10; ///< per axis

private:
  static constexpr float kLast = float((1 << kBits) - 1); // the last grid cell along an axis

  uint32_t code(Vec3f p) const {
    const Vec3f d = p - lower_;
    return kSpread[uint32_t(clampf(d.x * scale_.x, 0.f, kLast))] |
           kSpread[uint32_t(clampf(d.y * scale_.y, 0.f, kLast))] << 1 |
           kSpread[uint32_t(clampf(d.z * scale_.z, 0.f, kLast))] << 2;
  }

  /// spreadBits3 (core/morton.h) of each 10-bit coordinate: three table loads make a code, far fewer
  /// instructions than spreading the bits, for millions of cells.
  static constexpr std::array<uint32_t, 1 << kBits> kSpread = [] {
    std::array<uint32_t, 1 << kBits> table{};
    for (uint32_t v = 0; v < table.size(); ++v)
      for (int bit = 0; bit < kBits; ++bit)
        table[v] |= (v >> bit & 1u) << (3 * bit);
    return table;
  }();

  Vec3f lower_, scale_;
};

/// The order of one type array's cells by their keys (order[newIndex] = oldIndex), or an empty buffer when
/// the cells are in that order already. Leaves the keys in no useful order.
Buffer<uint32_t> sortedOrder(Buffer<uint64_t> &keys);

/// Item i of `items` becomes item order[i] of `source` (item i where `order` is empty: in order already), for
/// `count` items of `Stride` elements (a constant, so that an item's copy is a few moves and no memmove
/// call); in parallel. The order jumps all over `source`, so the loop asks for a later item early.
template <size_t Stride, typename T>
void gather(T *items, const T *source, size_t count, std::span<const uint32_t> order) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 12), [&](const tbb::blocked_range<size_t> &r) {
    constexpr size_t kPrefetchItems = 32;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      if (!order.empty() && i + kPrefetchItems < r.end())
        __builtin_prefetch(source + size_t(order[i + kPrefetchItems]) * Stride);
      const size_t from = order.empty() ? i : size_t(order[i]);
      for (size_t k = 0; k < Stride; ++k)
        items[i * Stride + k] = source[from * Stride + k];
    }
  });
}

/// Numbers the points by first use in the cells' order (points no cell uses keep their relative order at the
/// end), so that a cell's corners lie close in memory. The cells are renumbered as they are placed in their
/// final order, type array by type array in the mesh's type order; the points and point fields follow last.
class FirstUseNumbering {
public:
  explicit FirstUseNumbering(size_t pointCount) : newIndex_(pointCount, kUnused) {}

  /// Cell i of `cells` becomes cell order[i] of `source` (cell i where `order` is empty: `source` may then be
  /// `cells`), its corners renumbered, for `count` cells of `Corners` corners (a constant, as in gather).
  /// Numbers go by first use, which is serial; so the second half of the cells is numbered on its own
  /// meanwhile, from 0, and its numbers are then mapped to those that follow from the first half.
  template <size_t Corners>
  void place(uint32_t *cells, const uint32_t *source, size_t count, std::span<const uint32_t> order) {
    const size_t half = count >= kSplitCells ? count / 2 : count;
    std::vector<uint32_t> secondHalfIndex;
    uint32_t secondHalfPoints = 0;
    tbb::parallel_invoke(
        [&] { next_ = number<Corners>(cells, source, order, 0, half, newIndex_.data(), next_); },
        [&] {
          if (half == count)
            return;
          secondHalfIndex.assign(newIndex_.size(), kUnused);
          secondHalfPoints = number<Corners>(cells, source, order, half, count, secondHalfIndex.data(), 0);
        });
    if (half < count)
      renumberAfterFirstHalf(cells + half * Corners, (count - half) * Corners, secondHalfIndex,
                             secondHalfPoints);
  }

  /// Moves the points and point fields to their new numbers; once, after the last cells are placed.
  void reorderPoints(Mesh &mesh);

  /// `to` holds an item for each point the placed cells use, at its new number, taken from `from` (an item
  /// per old point); for cells placed from a mesh's selection, once, after the last are placed.
  template <typename T> void gatherUsed(std::span<const T> from, UninitVector<T> &to) const {
    to.resize(next_);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, from.size(), 1 << 16),
                      [&](const tbb::blocked_range<size_t> &r) {
                        for (size_t i = r.begin(); i < r.end(); ++i)
                          if (newIndex_[i] != kUnused)
                            to[newIndex_[i]] = from[i];
                      });
  }

private:
  static constexpr uint32_t kUnused = 0xffffffffu;
  static constexpr size_t kSplitCells = size_t(1) << 16;

  /// Places cells [begin, end), numbering points not in `newIndex` yet from `next` on; returns the next
  /// number. The order jumps all over the source cells, and their points' numbers are as scattered: the loop
  /// asks for a later cell's corners early, and for their numbers once those corners have arrived.
  template <size_t Corners>
  static uint32_t number(uint32_t *cells, const uint32_t *source, std::span<const uint32_t> order,
                         size_t begin, size_t end, uint32_t *newIndex, uint32_t next) {
    constexpr size_t kPrefetchCells = 16;
    auto sourceCell = [&](size_t i) { return source + (order.empty() ? i : size_t(order[i])) * Corners; };
    for (size_t i = begin; i < end; ++i) {
      if (i + 2 * kPrefetchCells < end)
        __builtin_prefetch(sourceCell(i + 2 * kPrefetchCells));
      if (i + kPrefetchCells < end)
        for (size_t k = 0; k < Corners; ++k)
          __builtin_prefetch(newIndex + sourceCell(i + kPrefetchCells)[k]);
      const uint32_t *from = sourceCell(i);
      for (size_t k = 0; k < Corners; ++k) {
        uint32_t &index = newIndex[from[k]];
        if (index == kUnused)
          index = next++;
        cells[i * Corners + k] = index;
      }
    }
    return next;
  }

  /// Maps the `count` corner numbers of the second half, numbered on their own by `ownIndex` (`ownPoints`
  /// points), to the numbers that go on from the first half's.
  void renumberAfterFirstHalf(uint32_t *corners, size_t count, const std::vector<uint32_t> &ownIndex,
                              uint32_t ownPoints);

  std::vector<uint32_t> newIndex_;
  uint32_t next_ = 0;
};

} // namespace uvr
