// Wall-clock timing in milliseconds.
#pragma once

#include <chrono>

namespace uvr {

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
