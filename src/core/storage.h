// Where a structure's arrays live. Structures shared by the backends take a storage as a template parameter:
// host vectors here, device buffers in the CUDA backend (DeviceStorage), so that each is described once and
// its views, byte counts and copies between host and device come from that one description.
#pragma once

#include <cstddef>
#include <type_traits>
#include <vector>

namespace uvr {

struct HostStorage {
  template <typename T> using Array = std::vector<T>;
};

/// The bytes an array of either storage holds.
template <typename Array> size_t arrayBytes(const Array &array) {
  return array.size() * sizeof(*array.data());
}

/// Its first element, or null where it is empty: views test for null.
template <typename Array> auto dataOrNull(const Array &array) -> decltype(array.data()) {
  return array.size() > 0 ? array.data() : nullptr;
}

/// Whether `T` is an array of some storage, rather than a plain value listed beside them (a grid's
/// placement, a box).
template <typename T, typename = void> struct IsStorageArray : std::false_type {};
template <typename T>
struct IsStorageArray<T,
                      std::void_t<decltype(std::declval<T &>().data()), decltype(std::declval<T &>().size())>>
    : std::true_type {};

/// Copies from one array to another of the same storage, or a plain value.
template <typename T> void copyMember(std::vector<T> &to, const std::vector<T> &from) { to = from; }
template <typename T, typename = std::enable_if_t<!IsStorageArray<T>::value>>
void copyMember(T &to, const T &from) {
  to = from;
}

/// The bytes held by `object`'s arrays, as its forEachMember lists them.
template <typename Object> size_t storageBytes(const Object &object) {
  size_t bytes = 0;
  Object::forEachMember(object, object, [&](const auto &member, const auto &) {
    if constexpr (IsStorageArray<std::remove_cvref_t<decltype(member)>>::value)
      bytes += arrayBytes(member);
  });
  return bytes;
}

/// Copies every member of `from` into `to`, both of one structure but of any two storages for which
/// copyMember is defined (host to host here; host to device and back in the CUDA backend).
template <typename To, typename From> void copyStorage(To &to, const From &from) {
  To::forEachMember(to, from, [](auto &a, const auto &b) { copyMember(a, b); });
}

} // namespace uvr
