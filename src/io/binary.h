// Packed binary values as files store them: unaligned, in either byte order. Shared by the readers; all
// inline, for their per-value loops.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace uvr {

/// `value` with its bytes in reverse order (any arithmetic type of 1, 2, 4 or 8 bytes).
template <typename T> inline T byteSwapped(T value) {
  static_assert(std::is_trivially_copyable_v<T>);
  // Through an unsigned integer of the same size: a byte-swap instruction, which vectorises (reversing the
  // bytes in an array did not, and made GCC 12 warn of overflows).
  if constexpr (sizeof(T) == 1) {
    return value;
  } else {
    using Bits =
        std::conditional_t<sizeof(T) == 2, uint16_t, std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>;
    static_assert(sizeof(T) == sizeof(Bits));
    Bits bits = std::bit_cast<Bits>(value);
    if constexpr (sizeof(T) == 2)
      bits = __builtin_bswap16(bits);
    else if constexpr (sizeof(T) == 4)
      bits = __builtin_bswap32(bits);
    else
      bits = __builtin_bswap64(bits);
    return std::bit_cast<T>(bits);
  }
}

/// The T whose bytes start at `bytes` (any alignment), in the machine's byte order.
template <typename T> inline T loadValue(const void *bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

/// The T whose bytes start at `bytes`, byte-swapped when `swap` (the file's order is not the machine's).
template <typename T> inline T loadValue(const void *bytes, bool swap) {
  const T value = loadValue<T>(bytes);
  return swap ? byteSwapped(value) : value;
}

/// Whether a file in big-endian order needs its values swapped on this machine.
inline constexpr bool kSwapBigEndian = std::endian::native == std::endian::little;

} // namespace uvr
