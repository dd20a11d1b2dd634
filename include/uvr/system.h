// What the library runs on: the threads its parallel loops use, and a wall-clock timer for statistics.
#pragma once

#include <uvr/settings.h>

#include <chrono>
#include <cstdint>
#include <string>

namespace uvr {

/// The threads the library's parallel loops use (all cores unless the process limits them).
int threadCount();
/// Limits the threads of every parallel loop in the process from now on, the library's and any other on
/// the same TBB (0: all cores again): one of several processes on a node takes its share of the cores.
/// Throws uvr::Error for a negative count.
void setThreadCount(int threads);

/// The most resident memory this process has held so far (getrusage's ru_maxrss), in bytes.
uint64_t hostPeakRssBytes();

/// The CUDA GPUs this process sees: 0 without the CUDA backend or a GPU.
int cudaDeviceCount();
/// Makes the CUDA backends prepared from now on run on GPU `ordinal` (GPU 0 by default, and where `ordinal`
/// is not below cudaDeviceCount()): one process per GPU picks its own. Throws uvr::Error for a negative one.
void setCudaDevice(int ordinal);

/// Makes the backends prepared from now on build `layout` (MemoryLayout::Auto by default).
void setMemoryLayout(MemoryLayout layout);
MemoryLayout memoryLayout();

/// The memory limit in bytes: what the library lets input inflate to (decompressed arrays, values a file
/// declares but does not hold, frame buffers) before refusing it with uvr::Error. The default is 4 GiB, or
/// the environment variable UVR_MEMORY_LIMIT (bytes, or with a K, M, G or T suffix) when set.
uint64_t memoryLimit();
/// Replaces the memory limit for the whole process (0: back to the default).
void setMemoryLimit(uint64_t bytes);
/// Parses a size such as 4096, 512M or 8G (binary units); throws uvr::Error naming `text` when malformed.
uint64_t parseByteSize(const std::string &text);

/// Wall-clock timing in milliseconds.
class Timer {
public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double milliseconds() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }

private:
  std::chrono::steady_clock::time_point start_;
};

} // namespace uvr
