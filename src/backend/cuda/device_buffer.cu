#include "backend/cuda/device_buffer.cuh"

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

void throwOutOfMemory(size_t bytes) {
  size_t free = 0, total = 0;
  cudaMemGetInfo(&free, &total);
  throw Error("GPU out of memory: asked for " + std::to_string(bytes) + " bytes, " + std::to_string(free) +
              " of " + std::to_string(total) + " free");
}

} // namespace uvr
