// Large arrays that start uninitialized, for loops that write them in full.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include <sys/mman.h>

namespace uvr {

/// Heap memory for `size` elements of T. Blocks of 2 MiB or more ask Linux for transparent huge pages: one
/// page fault per 2 MiB instead of one per 4 KiB. Released by std::free.
template <typename T> T *allocateArray(size_t size) {
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

/// A fixed-size heap array of T whose elements start uninitialized. A std::vector of the same size is zeroed
/// on one thread first, which also takes every page fault there; a Buffer's pages are faulted in by the loop
/// that fills it, on all of its threads.
template <typename T> class Buffer {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
  Buffer() = default;
  explicit Buffer(size_t size) : data_(allocateArray<T>(size)), size_(size) {}

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

  /// This buffer's memory as a Buffer of `size` U, which must fit in it; this one is left empty. For an array
  /// that is done with: the next one in its place takes no fresh pages, each of which the kernel would zero.
  template <typename U> Buffer<U> reuseAs(size_t size) && {
    static_assert(alignof(U) <= alignof(std::max_align_t)); // what malloc and allocateArray give
    if (size > size_ * sizeof(T) / sizeof(U))
      throw std::bad_alloc();
    size_ = 0;
    return Buffer<U>(reinterpret_cast<U *>(data_.release()), size);
  }

private:
  template <typename> friend class Buffer;

  Buffer(T *data, size_t size) : data_(data), size_(size) {}

  struct Free {
    void operator()(T *p) const { std::free(p); }
  };

  std::unique_ptr<T[], Free> data_;
  size_t size_ = 0;
};

/// A std::allocator whose elements, constructed without a value, are default-initialized: resize(n) and
/// vector(n) leave trivial values uninitialized, as a Buffer does, instead of zeroing them on one thread.
/// resize(n, value), vector(n, value) and the like still write the value.
template <typename T> struct DefaultInitAllocator {
  using value_type = T;

  DefaultInitAllocator() = default;
  template <typename U> DefaultInitAllocator(const DefaultInitAllocator<U> &) {}

  T *allocate(size_t n) { return allocateArray<T>(n); }
  void deallocate(T *p, size_t) { std::free(p); }

  template <typename U> void construct(U *p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void *>(p)) U;
  }
  template <typename U, typename... Args> void construct(U *p, Args &&...args) {
    ::new (static_cast<void *>(p)) U(std::forward<Args>(args)...);
  }

  template <typename U> bool operator==(const DefaultInitAllocator<U> &) const { return true; }
};

/// A std::vector of trivial values that starts uninitialized when sized (see DefaultInitAllocator): the
/// mesh's large arrays, filled by parallel loops.
template <typename T> using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

} // namespace uvr
