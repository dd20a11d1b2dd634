#include "backend/cuda/device_buffer.cuh"

#include <atomic>
#include <string>

namespace uvr {

void checkCuda(cudaError_t status, const char *call, const char *file, int line) {
  if (status == cudaSuccess)
    return;
  std::string what = std::string("CUDA: ") + call + " failed at " + file + ":" + std::to_string(line) + ": " +
                     cudaGetErrorString(status);
  if (status == cudaErrorMemoryAllocation) {
    size_t free = 0, total = 0;
    if (cudaMemGetInfo(&free, &total) == cudaSuccess)
      what += " (" + std::to_string(free) + " of " + std::to_string(total) + " bytes free)";
  }
  throw Error(what);
}

namespace {
constexpr int kPeakDevices = 64; // devices whose peaks are kept; others are not sampled
std::atomic<size_t> peakUsed[kPeakDevices];

int currentDevice() {
  int device = 0;
  UVR_CUDA_CHECK(cudaGetDevice(&device));
  return device;
}
} // namespace

size_t sampleDeviceMemory() {
  size_t free = 0, total = 0;
  UVR_CUDA_CHECK(cudaMemGetInfo(&free, &total));
  const size_t used = total - free;
  const int device = currentDevice();
  if (device < 0 || device >= kPeakDevices)
    return used;
  std::atomic<size_t> &peak = peakUsed[device];
  size_t seen = peak.load();
  while (used > seen && !peak.compare_exchange_weak(seen, used)) {
  }
  return used;
}

void resetDeviceMemoryPeak() {
  const int device = currentDevice();
  if (device >= 0 && device < kPeakDevices)
    peakUsed[device] = 0;
  sampleDeviceMemory();
}

size_t deviceMemoryPeak(int device) {
  return device >= 0 && device < kPeakDevices ? peakUsed[device].load() : 0;
}

void throwOutOfMemory(size_t bytes) {
  size_t free = 0, total = 0;
  cudaMemGetInfo(&free, &total);
  throw Error("GPU out of memory: asked for " + std::to_string(bytes) + " bytes, " + std::to_string(free) +
              " of " + std::to_string(total) + " free");
}

} // namespace uvr
