// The numeric element types of the formats' arrays, and the loops that read them: the run-time type tag is
// turned into a C++ type once per array (visitScalarType), and the per-value loops are templates on it, all
// inline, with no per-value dispatch.
#pragma once

#include "io/binary.h"
#include "io/text_scan.h"

#include <cstdint>
#include <type_traits>

namespace uvr {

enum class ScalarType : uint8_t {
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Int64,
  UInt64,
  Float32,
  Float64
};

/// Calls `f` with a zero of the C++ type that `type` names, and returns what it returns.
template <typename F> inline decltype(auto) visitScalarType(ScalarType type, F &&f) {
  switch (type) {
  case ScalarType::Int8:
    return f(int8_t{});
  case ScalarType::UInt8:
    return f(uint8_t{});
  case ScalarType::Int16:
    return f(int16_t{});
  case ScalarType::UInt16:
    return f(uint16_t{});
  case ScalarType::Int32:
    return f(int32_t{});
  case ScalarType::UInt32:
    return f(uint32_t{});
  case ScalarType::Int64:
    return f(int64_t{});
  case ScalarType::UInt64:
    return f(uint64_t{});
  case ScalarType::Float32:
    return f(float{});
  case ScalarType::Float64:
    break;
  }
  return f(double{});
}

/// Bytes of one packed value of `type`.
inline uint64_t scalarSize(ScalarType type) {
  return visitScalarType(type, [](auto zero) { return uint64_t(sizeof(zero)); });
}

inline bool isInteger(ScalarType type) { return type != ScalarType::Float32 && type != ScalarType::Float64; }

/// The ScalarType of the C++ type T.
template <typename T> constexpr ScalarType scalarTypeOf() {
  if constexpr (std::is_same_v<T, int8_t>)
    return ScalarType::Int8;
  else if constexpr (std::is_same_v<T, uint8_t>)
    return ScalarType::UInt8;
  else if constexpr (std::is_same_v<T, int16_t>)
    return ScalarType::Int16;
  else if constexpr (std::is_same_v<T, uint16_t>)
    return ScalarType::UInt16;
  else if constexpr (std::is_same_v<T, int32_t>)
    return ScalarType::Int32;
  else if constexpr (std::is_same_v<T, uint32_t>)
    return ScalarType::UInt32;
  else if constexpr (std::is_same_v<T, int64_t>)
    return ScalarType::Int64;
  else if constexpr (std::is_same_v<T, uint64_t>)
    return ScalarType::UInt64;
  else if constexpr (std::is_same_v<T, float>)
    return ScalarType::Float32;
  else {
    static_assert(std::is_same_v<T, double>, "not a type of the formats' arrays");
    return ScalarType::Float64;
  }
}

/// How values become the Dst that a reader stores: as C++ converts them.
template <typename Dst> struct CastTo {
  template <typename Value> Dst operator()(Value value) const { return static_cast<Dst>(value); }
};

/// Converts `count` packed values of `type` at `src` (byte-swapped when `swap`) to Dst by `to`.
template <typename Dst, typename To = CastTo<Dst>>
inline void convertPacked(ScalarType type, bool swap, const uint8_t *src, uint64_t count, Dst *dst,
                          const To &to = {}) {
  visitScalarType(type, [&](auto zero) {
    using Src = decltype(zero);
    const To local = to; // whose members no write to dst can change: the loop need not load them again
    for (uint64_t i = 0; i < count; ++i)
      dst[i] = local(loadValue<Src>(src + i * sizeof(Src), swap));
  });
}

/// The type in which text of a Src array is parsed: double for floating types, uint64_t for UInt64 and
/// int64_t for the other integers.
template <typename Src>
using ParsedAs = std::conditional_t<std::is_floating_point_v<Src>, double,
                                    std::conditional_t<std::is_same_v<Src, uint64_t>, uint64_t, int64_t>>;

/// Parses all of [first, last) as a value of `type` (see ParsedAs) and stores it in `out` converted by `to`
/// (also when the text is not such a number); false when it is not.
template <typename Dst, typename To = CastTo<Dst>>
inline bool parseScalar(ScalarType type, const char *first, const char *last, Dst &out, const To &to = {}) {
  return visitScalarType(type, [&](auto zero) {
    ParsedAs<decltype(zero)> value{};
    const bool ok = parseNumber(first, last, value);
    out = to(value);
    return ok;
  });
}

} // namespace uvr
