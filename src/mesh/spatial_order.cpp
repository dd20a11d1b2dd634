#include "mesh/spatial_order.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

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

/// Writes [begin, end) to out ordered by one digit, ties in their order: the keys, or as Out = uint32_t their
/// indices.
template <typename Out> void countingSort(const uint64_t *begin, const uint64_t *end, Out *out, int shift) {
  std::array<size_t, kBuckets> next{};
  for (const uint64_t *key = begin; key != end; ++key)
    ++next[digit(*key, shift)];
  size_t position = 0;
  for (size_t &n : next)
    position += std::exchange(n, position);
  for (const uint64_t *key = begin; key != end; ++key)
    out[next[digit(*key, shift)]++] = Out(*key);
}

/// The indices of keys (code << 32 | index) sorted by their code, ties in index order. A stable radix sort on
/// the code's 30 bits, three digits of 10: first by the top digit, in parallel over chunks of keys (each
/// chunk counts its digits, then writes its keys after those of earlier chunks with the same digit); then
/// each of the 1024 runs of equal top digits by the lower two, in parallel over runs, each small enough to
/// stay in cache. The last pass writes the indices alone. The keys are left in no useful order.
Buffer<uint32_t> radixSortedIndices(Buffer<uint64_t> &keys) {
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
  Buffer<uint32_t> indices(keys.size());
  tbb::parallel_for(size_t(0), kBuckets, [&](size_t b) {
    const size_t first = runStart[b], last = runStart[b + 1];
    countingSort(scratch.data() + first, scratch.data() + last, keys.data() + first, kLowShift);
    countingSort(keys.data() + first, keys.data() + last, indices.data() + first, kLowShift + kDigitBits);
  });
  return indices;
}

/// A copy of items [0, count), made in parallel.
template <typename T> Buffer<T> copyOf(const T *items, size_t count) {
  Buffer<T> copy(count);
  parallelChunks(count, 1 << 16, [&](size_t begin, size_t end) {
    std::copy(items + begin, items + end, copy.data() + begin);
  });
  return copy;
}

/// Item offset + i becomes the old item offset + order[i].
template <typename T>
void permute(UninitVector<T> &values, std::span<const uint32_t> order, size_t offset = 0) {
  T *items = values.data() + offset;
  const Buffer<T> old = copyOf(items, order.size());
  gather<1>(items, old.data(), order.size(), order);
}

} // namespace

Buffer<uint32_t> sortedOrder(Buffer<uint64_t> &keys) {
  if (std::is_sorted(keys.begin(), keys.end()))
    return {};
  return radixSortedIndices(keys);
}

namespace {

/// The indices i of `keep` where keep[i] is nonzero, in order; in parallel, block by block.
Buffer<uint32_t> keptIndices(std::span<const uint8_t> keep) {
  constexpr size_t kBlock = size_t(1) << 16;
  const size_t blocks = (keep.size() + kBlock - 1) / kBlock;
  std::vector<size_t> start(blocks + 1, 0); // each block's count at b + 1, then where its indices go
  parallelChunks(blocks, 1, [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b)
      start[b + 1] = size_t(std::count_if(keep.begin() + ptrdiff_t(b * kBlock),
                                          keep.begin() + ptrdiff_t(std::min(keep.size(), (b + 1) * kBlock)),
                                          [](uint8_t k) { return k != 0; }));
  });
  for (size_t b = 0; b < blocks; ++b)
    start[b + 1] += start[b];
  Buffer<uint32_t> indices(start[blocks]);
  parallelChunks(blocks, 1, [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b) {
      size_t out = start[b];
      for (size_t i = b * kBlock; i < std::min(keep.size(), (b + 1) * kBlock); ++i)
        if (keep[i] != 0)
          indices[out++] = uint32_t(i);
    }
  });
  return indices;
}

} // namespace

Mesh selectCells(const Mesh &mesh, std::span<const uint8_t> keep, std::span<const int> fields) {
  // Each type array's kept cells, as indices into it: the order in which place and gather copy them.
  std::array<Buffer<uint32_t>, 4> kept;
  const std::array<size_t, 4> counts = {mesh.tetCount(), mesh.pyramidCount(), mesh.wedgeCount(),
                                        mesh.hexCount()};
  size_t firstCell = 0, keptCells = 0;
  for (size_t t = 0; t < kept.size(); ++t) {
    kept[t] = keptIndices(keep.subspan(firstCell, counts[t]));
    firstCell += counts[t];
    keptCells += kept[t].size();
  }

  Mesh piece;
  FirstUseNumbering numbering(mesh.points.size());
  auto placeCells = [&]<size_t Corners>(size_t t, const UninitVector<uint32_t> &from,
                                        UninitVector<uint32_t> &to) {
    to.resize(kept[t].size() * Corners);
    if (!kept[t].empty())
      numbering.place<Corners>(to.data(), from.data(), kept[t].size(), kept[t]);
  };
  placeCells.operator()<4>(0, mesh.tets, piece.tets);
  placeCells.operator()<5>(1, mesh.pyramids, piece.pyramids);
  placeCells.operator()<6>(2, mesh.wedges, piece.wedges);
  placeCells.operator()<8>(3, mesh.hexes, piece.hexes);
  numbering.gatherUsed<Vec3f>(mesh.points, piece.points);
  for (const int f : fields) {
    const ScalarField &field = mesh.fields[size_t(f)];
    ScalarField &values =
        piece.fields.emplace_back(ScalarField{field.name, field.centering, {}, field.components});
    if (field.centering == Centering::Point) {
      numbering.gatherUsed<float>(field.values, values.values);
      continue;
    }
    values.values.resize(keptCells);
    size_t from = 0, to = 0;
    for (size_t t = 0; t < kept.size(); ++t) {
      if (!kept[t].empty())
        gather<1>(values.values.data() + to, field.values.data() + from, kept[t].size(), kept[t]);
      from += counts[t];
      to += kept[t].size();
    }
  }
  return piece;
}

void FirstUseNumbering::renumberAfterFirstHalf(uint32_t *corners, size_t count,
                                               const std::vector<uint32_t> &ownIndex, uint32_t ownPoints) {
  // The second half's points in the order it first used them, then the number each gets overall: its own
  // number where the first half did not use it.
  Buffer<uint32_t> overall(ownPoints);
  parallelChunks(ownIndex.size(), 1 << 16, [&](size_t begin, size_t end) {
    for (size_t point = begin; point < end; ++point)
      if (ownIndex[point] != kUnused)
        overall[ownIndex[point]] = uint32_t(point);
  });
  for (uint32_t &number : overall) {
    uint32_t &index = newIndex_[number];
    if (index == kUnused)
      index = next_++;
    number = index;
  }
  parallelChunks(count, 1 << 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      corners[i] = overall[corners[i]];
  });
}

void FirstUseNumbering::reorderPoints(Mesh &mesh) {
  for (uint32_t &index : newIndex_)
    if (index == kUnused)
      index = next_++;
  Buffer<uint32_t> order(newIndex_.size()); // the inverse permutation, written in parallel
  parallelChunks(order.size(), 1 << 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      order[newIndex_[i]] = uint32_t(i);
  });
  permute(mesh.points, order);
  for (ScalarField &field : mesh.fields)
    if (field.centering == Centering::Point)
      permute(field.values, order);
}

void orderSpatially(Mesh &mesh) {
  if (mesh.points.empty())
    return;
  const CellKeys cellKeys(mesh.bounds());

  // Cells: each type array on its own, so that the type order (and thus cell indices' meaning) is kept.
  FirstUseNumbering numbering(mesh.points.size());
  size_t firstCell = 0;
  auto orderCells = [&]<size_t Corners>(UninitVector<uint32_t> &cells) {
    const size_t count = cells.size() / Corners;
    Buffer<uint64_t> keys(count);
    parallelChunks(count, 1 << 12, [&](size_t begin, size_t end) {
      for (size_t c = begin; c < end; ++c)
        keys[c] = cellKeys.key(&cells[c * Corners], int(Corners), mesh.points, c);
    });
    const Buffer<uint32_t> order = sortedOrder(keys);
    keys = Buffer<uint64_t>(); // freed before the cells are copied
    if (order.empty()) {
      numbering.place<Corners>(cells.data(), cells.data(), count, order);
    } else {
      numbering.place<Corners>(cells.data(), copyOf(cells.data(), cells.size()).data(), count, order);
      for (ScalarField &field : mesh.fields)
        if (field.centering == Centering::Cell)
          permute(field.values, order, firstCell);
    }
    firstCell += count;
  };
  orderCells.operator()<4>(mesh.tets);
  orderCells.operator()<5>(mesh.pyramids);
  orderCells.operator()<6>(mesh.wedges);
  orderCells.operator()<8>(mesh.hexes);
  numbering.reorderPoints(mesh);
}

} // namespace uvr
