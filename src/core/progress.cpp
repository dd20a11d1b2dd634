#include "core/progress.h"

#include <cstdio>
#include <unistd.h>

namespace uvr {

Progress::Progress(std::string label, uint64_t total)
    : label_(std::move(label)), total_(total), start_(std::chrono::steady_clock::now()),
      enabled_(isatty(fileno(stderr)) != 0) {}

Progress::~Progress() { finish(); }

void Progress::advance(uint64_t amount) { report(done_.fetch_add(amount) + amount); }

void Progress::set(uint64_t done) {
  uint64_t previous = done_.load();
  while (done > previous && !done_.compare_exchange_weak(previous, done)) {
  }
  report(done);
}

void Progress::report(uint64_t done) {
  if (!enabled_)
    return;
  const int64_t nowMs =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start_)
          .count();
  int64_t last = lastDrawMs_.load();
  // Only long work is worth a line; then redraw every 200 ms from one thread at a time.
  if (nowMs < 500 || nowMs - last < 200 || !lastDrawMs_.compare_exchange_strong(last, nowMs))
    return;
  draw(done);
}

void Progress::draw(uint64_t done) {
  const double fraction = total_ ? double(done) / double(total_) : 1.0;
  std::fprintf(stderr, "\r%s: %5.1f%%", label_.c_str(), 100.0 * (fraction > 1.0 ? 1.0 : fraction));
  std::fflush(stderr);
}

void Progress::finish() {
  if (finished_)
    return;
  finished_ = true;
  if (enabled_ && lastDrawMs_.load() > 0) {
    draw(total_);
    std::fputc('\n', stderr);
  }
}

} // namespace uvr
