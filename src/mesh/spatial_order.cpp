#include "mesh/mesh.h"

#include "core/buffer.h"
#include "core/morton.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <span>
#include <utility>

namespace uvr {
namespace {

// A 30-bit Morton code (a 1024³ grid over the mesh bounds): fine enough to order a billion cells for
// locality, and small enough to sit beside a 32-bit cell index in one 64-bit key.
constexpr int kMortonBits = 10;
constexpr float kMortonLast = float((1 << kMortonBits) - 1); // the last grid cell along an axis

struct MortonQuantizer {
  Vec3f lower, scale;

  explicit MortonQuantizer(const Box3f &box) : lower(box.lower) {
    const Vec3f extent = box.upper - box.lower;
    scale = {extent.x > 0.f ? kMortonLast / extent.x : 0.f, extent.y > 0.f ? kMortonLast / extent.y : 0.f,
             extent.z > 0.f ? kMortonLast / extent.z : 0.f};
  }
  uint32_t code(Vec3f p) const {
    const Vec3f d = p - lower;
    return uint32_t(mortonCode(uint32_t(clampf(d.x * scale.x, 0.f, kMortonLast)),
                               uint32_t(clampf(d.y * scale.y, 0.f, kMortonLast)),
                               uint32_t(clampf(d.z * scale.z, 0.f, kMortonLast))));
  }
};

/// Runs f(begin, end) over [0, n) in parallel, in chunks of `grain` or more.
template <typename F> void parallelChunks(size_t n, size_t grain, F &&f) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                    [&](const tbb::blocked_range<size_t> &r) { f(r.begin(), r.end()); });
}

/// Sorts keys (code << 32 | index) by their code, ties in index order: a stable LSD radix sort on the code's
/// 30 bits, three passes of 10. Each pass is parallel over fixed chunks of keys: each chunk counts its
/// digits, and then writes its keys after those of the earlier chunks with the same digit.
void radixSortByCode(Buffer<uint64_t> &keys) {
  constexpr int kDigitBits = 10;
  constexpr size_t kBuckets = size_t(1) << kDigitBits;
  constexpr size_t kChunkKeys = size_t(1) << 16;
  const size_t chunkCount = (keys.size() + kChunkKeys - 1) / kChunkKeys;
  Buffer<uint64_t> scratch(keys.size());
  std::vector<std::array<size_t, kBuckets>> next(
      chunkCount); // per chunk: where its next key of each digit goes
  for (int shift = 32; shift < 32 + 3 * kMortonBits; shift += kDigitBits) {
    auto digit = [shift](uint64_t key) { return size_t(key >> shift) & (kBuckets - 1); };
    auto forEachChunk = [&](auto &&body) {
      tbb::parallel_for(size_t(0), chunkCount, [&](size_t k) {
        body(next[k], keys.data() + k * kChunkKeys,
             keys.data() + std::min(keys.size(), (k + 1) * kChunkKeys));
      });
    };
    forEachChunk([&](std::array<size_t, kBuckets> &count, const uint64_t *begin, const uint64_t *end) {
      count.fill(0);
      for (const uint64_t *key = begin; key != end; ++key)
        ++count[digit(*key)];
    });
    size_t position = 0;
    for (size_t b = 0; b < kBuckets; ++b)
      for (std::array<size_t, kBuckets> &count : next)
        position += std::exchange(count[b], position);
    forEachChunk([&](std::array<size_t, kBuckets> &position, const uint64_t *begin, const uint64_t *end) {
      for (const uint64_t *key = begin; key != end; ++key)
        scratch[position[digit(*key)]++] = *key;
    });
    std::swap(keys, scratch);
  }
}

/// Sorts the cells of one type array by the Morton code of their centroids; returns the new order
/// (order[newIndex] = oldIndex), or an empty buffer when the cells are already in that order.
Buffer<uint32_t> mortonOrder(const std::vector<uint32_t> &cells, int corners,
                             const std::vector<Vec3f> &points, const MortonQuantizer &quantizer) {
  const size_t count = cells.size() / size_t(corners);
  Buffer<uint64_t> keys(count);
  parallelChunks(count, 1 << 12, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      Vec3f sum{0.f, 0.f, 0.f};
      for (int i = 0; i < corners; ++i)
        sum = sum + points[cells[c * size_t(corners) + size_t(i)]];
      keys[c] = uint64_t(quantizer.code(sum * (1.f / float(corners)))) << 32 | uint64_t(c);
    }
  });
  if (std::is_sorted(keys.begin(), keys.end()))
    return {};
  radixSortByCode(keys);
  Buffer<uint32_t> order(count);
  parallelChunks(count, 1 << 12, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      order[i] = uint32_t(keys[i]);
  });
  return order;
}

/// Item offset + i becomes the old item offset + order[i], for items of `Stride` elements (a constant, so
/// that an item's copy is a few moves and no memmove call).
template <size_t Stride, typename T>
void permute(std::vector<T> &values, std::span<const uint32_t> order, size_t offset = 0) {
  T *items = values.data() + offset * Stride;
  Buffer<T> old(order.size() * Stride);
  parallelChunks(old.size(), 1 << 16, [&](size_t begin, size_t end) {
    std::copy(items + begin, items + end, old.data() + begin);
  });
  parallelChunks(order.size(), 1 << 12, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      for (size_t k = 0; k < Stride; ++k)
        items[i * Stride + k] = old[size_t(order[i]) * Stride + k];
  });
}

} // namespace

void orderSpatially(Mesh &mesh) {
  if (mesh.points.empty())
    return;
  const MortonQuantizer quantizer(mesh.bounds());

  // Cells: each type array on its own, so that the type order (and thus cell indices' meaning) is kept.
  size_t firstCell = 0;
  auto orderCells = [&]<size_t Corners>(std::vector<uint32_t> &cells) {
    const Buffer<uint32_t> order = mortonOrder(cells, int(Corners), mesh.points, quantizer);
    if (!order.empty()) {
      permute<Corners>(cells, order);
      for (ScalarField &field : mesh.fields)
        if (field.centering == Centering::Cell)
          permute<1>(field.values, order, firstCell);
    }
    firstCell += cells.size() / Corners;
  };
  orderCells.operator()<4>(mesh.tets);
  orderCells.operator()<5>(mesh.pyramids);
  orderCells.operator()<6>(mesh.wedges);
  orderCells.operator()<8>(mesh.hexes);

  // Points: numbered by first use in the new cell order, so that a cell's corners lie close in memory.
  constexpr uint32_t kUnused = 0xffffffffu;
  std::vector<uint32_t> newIndex(mesh.points.size(), kUnused);
  uint32_t next = 0;
  for (std::vector<uint32_t> *cells : {&mesh.tets, &mesh.pyramids, &mesh.wedges, &mesh.hexes})
    for (uint32_t &v : *cells) {
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
  permute<1>(mesh.points, order);
  for (ScalarField &field : mesh.fields)
    if (field.centering == Centering::Point)
      permute<1>(field.values, order);
}

} // namespace uvr
