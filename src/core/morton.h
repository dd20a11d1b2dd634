// Morton (Z-order) codes: three coordinates of up to 21 bits interleaved into one 63-bit key.
#pragma once

#include "core/host_device.h"

#include <cstdint>

namespace uvr {

/// Spreads the low 21 bits of `v` so that two zero bits follow each.
UVR_HOST_DEVICE inline uint64_t spreadBits3(uint32_t v) {
  uint64_t x = v & 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

/// The inverse of spreadBits3: every third bit of `x`, from bit 0.
UVR_HOST_DEVICE inline uint32_t compactBits3(uint64_t x) {
  x &= 0x1249249249249249ull;
  x = (x ^ (x >> 2)) & 0x10c30c30c30c30c3ull;
  x = (x ^ (x >> 4)) & 0x100f00f00f00f00full;
  x = (x ^ (x >> 8)) & 0x1f0000ff0000ffull;
  x = (x ^ (x >> 16)) & 0x1f00000000ffffull;
  x = (x ^ (x >> 32)) & 0x1fffffull;
  return uint32_t(x);
}

/// The Morton code of (x, y, z), each below 2^21; x takes the lowest bit.
UVR_HOST_DEVICE inline uint64_t mortonCode(uint32_t x, uint32_t y, uint32_t z) {
  return spreadBits3(x) | spreadBits3(y) << 1 | spreadBits3(z) << 2;
}

} // namespace uvr
