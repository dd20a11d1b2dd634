// What the library runs on: the threads its parallel loops use, and a wall-clock timer for statistics.
#pragma once

#include <chrono>

namespace uvr {

/// The threads the library's parallel loops use (all cores unless the process limits them).
int threadCount();

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
