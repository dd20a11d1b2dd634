// Checked CUDA calls and owned device allocations, for the CUDA backend's sources.
#pragma once

#include <uvr/error.h>

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

/// Throws uvr::Error naming the call and the place unless `status` is cudaSuccess.
void checkCuda(cudaError_t status, const char *call, const char *file, int line);
#define UVR_CUDA_CHECK(call) ::uvr::checkCuda((call), #call, __FILE__, __LINE__)

/// Throws uvr::Error saying how much memory was asked for and how much is free.
[[noreturn]] void throwOutOfMemory(size_t bytes);

/// The GPU memory in use on the current device now (total - free from cudaMemGetInfo: every allocation of
/// every process, and the CUDA context), folded into that device's peak. Called after each allocation.
size_t sampleDeviceMemory();
/// Starts the current device's peak anew at what is in use now.
void resetDeviceMemoryPeak();
/// The highest sample on `device` since its last reset.
size_t deviceMemoryPeak(int device);

/// One device allocation, freed with its owner.
template <typename T> class DeviceBuffer {
public:
  DeviceBuffer() = default;
  ~DeviceBuffer() { cudaFree(data_); }
  DeviceBuffer(const DeviceBuffer &) = delete;
  DeviceBuffer &operator=(const DeviceBuffer &) = delete;

  /// Holds exactly `count` elements afterwards; the contents are lost when the size changes.
  void resize(size_t count) {
    if (count == count_)
      return;
    release();
    if (count == 0)
      return;
    if (cudaMalloc(&data_, count * sizeof(T)) != cudaSuccess) {
      cudaGetLastError(); // clear the sticky state before reporting
      data_ = nullptr;
      throwOutOfMemory(count * sizeof(T));
    }
    count_ = count;
    sampleDeviceMemory();
  }
  /// Holds at least `count` elements afterwards, keeping the first `keep`; grows by half again at least, so
  /// that a buffer filled piece by piece is copied a few times only.
  void grow(size_t count, size_t keep) {
    if (count <= count_)
      return;
    DeviceBuffer larger;
    larger.resize(count + count / 2);
    if (keep > 0)
      UVR_CUDA_CHECK(cudaMemcpy(larger.data_, data_, keep * sizeof(T), cudaMemcpyDeviceToDevice));
    swap(larger);
  }
  void release() {
    cudaFree(data_);
    data_ = nullptr;
    count_ = 0;
  }
  void swap(DeviceBuffer &other) {
    std::swap(data_, other.data_);
    std::swap(count_, other.count_);
  }
  /// Copies `count` elements from host memory (allocating as needed); returns the device pointer.
  T *upload(const T *host, size_t count) {
    resize(count);
    if (count > 0)
      UVR_CUDA_CHECK(cudaMemcpy(data_, host, count * sizeof(T), cudaMemcpyHostToDevice));
    return data_;
  }
  void download(T *host, size_t count) const {
    if (count > 0)
      UVR_CUDA_CHECK(cudaMemcpy(host, data_, count * sizeof(T), cudaMemcpyDeviceToHost));
  }
  T *data() const { return data_; }
  size_t size() const { return count_; }
  size_t bytes() const { return count_ * sizeof(T); }

private:
  T *data_ = nullptr;
  size_t count_ = 0;
};

/// Acceleration structures in device memory (see core/storage.h).
struct DeviceStorage {
  template <typename T> using Array = DeviceBuffer<T>;
};

/// Copies between host and device arrays, for copyStorage.
template <typename T> void copyMember(DeviceBuffer<T> &to, const std::vector<T> &from) {
  to.upload(from.data(), from.size());
}
template <typename T> void copyMember(std::vector<T> &to, const DeviceBuffer<T> &from) {
  to.resize(from.size());
  from.download(to.data(), to.size());
}

inline unsigned blocksFor(uint64_t threads, int block) {
  return unsigned((threads + uint64_t(block) - 1) / uint64_t(block));
}

/// Temporary storage for cub's device-wide algorithms, kept across calls: `algorithm(storage, bytes)` is
/// called once with no storage to size it, then with it.
class CubScratch {
public:
  template <typename Run> void run(Run &&algorithm) {
    size_t bytes = 0;
    UVR_CUDA_CHECK(algorithm(nullptr, bytes));
    storage_.grow(bytes, 0);
    UVR_CUDA_CHECK(algorithm(storage_.data(), bytes));
  }

private:
  DeviceBuffer<uint8_t> storage_;
};

} // namespace uvr
