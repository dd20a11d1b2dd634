// The box around many points or boxes, reduced in parallel on the host.
#pragma once

#include "core/vec.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cstdint>

namespace uvr {

/// The box around `boundsOf(i)` (a point or a box) for i in [0, count). Exact whatever the split, since min
/// and max do not round; short ranges stay serial, where spawning tasks would cost more than it saves.
template <typename BoundsOf> Box3f parallelBounds(uint64_t count, const BoundsOf &boundsOf) {
  constexpr uint64_t kSerialCount = 1 << 14;
  auto extend = [&](uint64_t begin, uint64_t end, Box3f box) {
    for (uint64_t i = begin; i < end; ++i)
      box.extend(boundsOf(i));
    return box;
  };
  if (count < kSerialCount)
    return extend(0, count, Box3f{});
  return tbb::parallel_reduce(
      tbb::blocked_range<uint64_t>(0, count), Box3f{},
      [&](const tbb::blocked_range<uint64_t> &range, Box3f box) {
        return extend(range.begin(), range.end(), box);
      },
      [](Box3f a, const Box3f &b) {
        a.extend(b);
        return a;
      });
}

} // namespace uvr
