#include "mesh/spatial_order.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <utility>

namespace uvr {
namespace {

/// Runs f(begin, end) over [0, n) in parallel, in chunks of `grain` or more.
template <typename F> void parallelChunks(size_t n, size_t grain, F &&f) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                    [&](const tbb::blocked_range<size_t> &r) { f(r.begin(), r.end()); });
}

constexpr int kDigitBits = 10; // a radix sort digit: one Morton coordinate's bits
constexpr size_t kBuckets = size_t(1) << kDigitBits;

size_t digit(uint64_t key, int shift) { return size_t(key >> shift) & (kBuckets - 1); }

/// Writes [begin, end) to out ordered by one digit, ties in their order.
void countingSort(const uint64_t *begin, const uint64_t *end, uint64_t *out, int shift) {
  std::array<size_t, kBuckets> next{};
  for (const uint64_t *key = begin; key != end; ++key)
    ++next[digit(*key, shift)];
  size_t position = 0;
  for (size_t &n : next)
    position += std::exchange(n, position);
  for (const uint64_t *key = begin; key != end; ++key)
    out[next[digit(*key, shift)]++] = *key;
}

/// Sorts keys (code << 32 | index) by their code, ties in index order. A stable radix sort on the code's 30
/// bits, three digits of 10: first by the top digit, in parallel over chunks of keys (each chunk counts its
/// digits, then writes its keys after those of earlier chunks with the same digit); then each of the 1024
/// runs of equal top digits by the lower two, in parallel over runs, each small enough to stay in cache.
void radixSortByCode(Buffer<uint64_t> &keys) {
  constexpr int kLowShift = 32, kTopShift = 32 + 2 * kDigitBits;
  constexpr size_t kChunkKeys = size_t(1) << 16;
  const size_t chunkCount = (keys.size() + kChunkKeys - 1) / kChunkKeys;
  Buffer<uint64_t> scratch(keys.size());
  std::vector<std::array<size_t, kBuckets>> next(
      chunkCount); // per chunk: where its next key of each digit goes
  auto forEachChunk = [&](auto &&body) {
    tbb::parallel_for(size_t(0), chunkCount, [&](size_t k) {
      body(next[k], keys.data() + k * kChunkKeys, keys.data() + std::min(keys.size(), (k + 1) * kChunkKeys));
    });
  };
  forEachChunk([&](std::array<size_t, kBuckets> &count, const uint64_t *begin, const uint64_t *end) {
    count.fill(0);
    for (const uint64_t *key = begin; key != end; ++key)
      ++count[digit(*key, kTopShift)];
  });
  std::array<size_t, kBuckets + 1> runStart{};
  size_t position = 0;
  for (size_t b = 0; b < kBuckets; ++b) {
    runStart[b] = position;
    for (std::array<size_t, kBuckets> &count : next)
      position += std::exchange(count[b], position);
  }
  runStart[kBuckets] = position;
  forEachChunk([&](std::array<size_t, kBuckets> &position, const uint64_t *begin, const uint64_t *end) {
    for (const uint64_t *key = begin; key != end; ++key)
      scratch[position[digit(*key, kTopShift)]++] = *key;
  });
  tbb::parallel_for(size_t(0), kBuckets, [&](size_t b) {
    const size_t first = runStart[b], last = runStart[b + 1];
    countingSort(scratch.data() + first, scratch.data() + last, keys.data() + first, kLowShift);
    countingSort(keys.data() + first, keys.data() + last, scratch.data() + first, kLowShift + kDigitBits);
  });
  std::swap(keys, scratch);
}

/// Item offset + i becomes the old item offset + order[i].
template <size_t Stride, typename T>
void permute(UninitVector<T> &values, std::span<const uint32_t> order, size_t offset = 0) {
  T *items = values.data() + offset * Stride;
  Buffer<T> old(order.size() * Stride);
  parallelChunks(old.size(), 1 << 16, [&](size_t begin, size_t end) {
    std::copy(items + begin, items + end, old.data() + begin);
  });
  gather<Stride>(items, old.data(), order.size(), order);
}

} // namespace

Buffer<uint32_t> sortedOrder(Buffer<uint64_t> &keys) {
  if (std::is_sorted(keys.begin(), keys.end()))
    return {};
  radixSortByCode(keys);
  Buffer<uint32_t> order(keys.size());
  parallelChunks(keys.size(), 1 << 12, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      order[i] = uint32_t(keys[i]);
  });
  return order;
}

void numberPointsByFirstUse(Mesh &mesh) {
  constexpr uint32_t kUnused = 0xffffffffu;
  std::vector<uint32_t> newIndex(mesh.points.size(), kUnused);
  uint32_t next = 0;
  for (UninitVector<uint32_t> *cells : {&mesh.tets, &mesh.pyramids, &mesh.wedges, &mesh.hexes})
    for (uint32_t &v : *cells) {
      if (newIndex[v] == kUnused)
        newIndex[v] = next++;
      v = newIndex[v];
    }
  for (uint32_t &index : newIndex)
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

void orderSpatially(Mesh &mesh) {
  if (mesh.points.empty())
    return;
  const CellKeys cellKeys(mesh.bounds());

  // Cells: each type array on its own, so that the type order (and thus cell indices' meaning) is kept.
  size_t firstCell = 0;
  auto orderCells = [&]<size_t Corners>(UninitVector<uint32_t> &cells) {
    const size_t count = cells.size() / Corners;
    Buffer<uint64_t> keys(count);
    parallelChunks(count, 1 << 12, [&](size_t begin, size_t end) {
      for (size_t c = begin; c < end; ++c)
        keys[c] = cellKeys.key(&cells[c * Corners], int(Corners), mesh.points, c);
    });
    const Buffer<uint32_t> order = sortedOrder(keys);
    if (!order.empty()) {
      permute<Corners>(cells, order);
      for (ScalarField &field : mesh.fields)
        if (field.centering == Centering::Cell)
          permute<1>(field.values, order, firstCell);
    }
    firstCell += count;
  };
  orderCells.operator()<4>(mesh.tets);
  orderCells.operator()<5>(mesh.pyramids);
  orderCells.operator()<6>(mesh.wedges);
  orderCells.operator()<8>(mesh.hexes);
  numberPointsByFirstUse(mesh);
}

} // namespace uvr
