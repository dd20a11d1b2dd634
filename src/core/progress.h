// Progress of long loads and builds, drawn on stderr when it is a terminal and silent otherwise.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

namespace uvr {

class Progress {
public:
  /// `total` is in any unit (bytes, cells); `label` names the work, e.g. "building partitions".
  Progress(std::string label, uint64_t total);
  ~Progress();
  Progress(const Progress &) = delete;
  Progress &operator=(const Progress &) = delete;

  /// Thread-safe; redraws at most a few times per second.
  void advance(uint64_t amount);
  /// Thread-safe; for work that reports how far it is rather than how much it did.
  void set(uint64_t done);
  void finish();

private:
  void report(uint64_t done);
  void draw(uint64_t done);

  std::string label_;
  uint64_t total_;
  std::atomic<uint64_t> done_{0};
  std::atomic<int64_t> lastDrawMs_{0};
  std::chrono::steady_clock::time_point start_;
  bool enabled_;
  bool finished_ = false;
};

} // namespace uvr
