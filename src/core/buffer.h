// Large arrays that start uninitialized, for loops that write them in full.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <span>
#include <type_traits>

#include <sys/mman.h>

namespace uvr {

/// A fixed-size heap array of T whose elements start uninitialized. A std::vector of the same size is zeroed
/// on one thread first, which also takes every page fault there; a Buffer's pages are faulted in by the loop
/// that fills it, on all of its threads. Buffers of 2 MiB or more ask Linux for transparent huge pages: one
/// page fault per 2 MiB instead of one per 4 KiB.
template <typename T> class Buffer {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
  Buffer() = default;
  explicit Buffer(size_t size) : data_(allocate(size)), size_(size) {}

  T *data() { return data_.get(); }
  const T *data() const { return data_.get(); }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T &operator[](size_t i) { return data_[i]; }
  const T &operator[](size_t i) const { return data_[i]; }
  T *begin() { return data(); }
  T *end() { return data() + size_; }
  const T *begin() const { return data(); }
  const T *end() const { return data() + size_; }
  operator std::span<const T>() const { return {data(), size_}; }

private:
  struct Free {
    void operator()(T *p) const { std::free(p); }
  };

  static T *allocate(size_t size) {
    constexpr size_t kHugePage = size_t(2) << 20;
    if (size > SIZE_MAX / sizeof(T))
      throw std::bad_alloc();
    size_t bytes = size * sizeof(T);
    void *p;
    if (bytes >= kHugePage) {
      bytes = (bytes + kHugePage - 1) / kHugePage * kHugePage; // aligned_alloc wants a multiple
      p = std::aligned_alloc(kHugePage, bytes);
#ifdef MADV_HUGEPAGE
      if (p)
        ::madvise(p, bytes, MADV_HUGEPAGE); // only a hint: without huge pages it is an ordinary array
#endif
    } else {
      p = std::malloc(bytes > 0 ? bytes : 1);
    }
    if (!p)
      throw std::bad_alloc();
    return static_cast<T *>(p);
  }

  std::unique_ptr<T[], Free> data_;
  size_t size_ = 0;
};

} // namespace uvr
