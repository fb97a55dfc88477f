#include "gui/rate_limiter.hpp"

#include <cmath>
#include <cstddef>

namespace concert::gui {

RateLimiter::RateLimiter(double max_hz)
    : max_hz_(max_hz), period_ns_(max_hz > 0 ? static_cast<int64_t>(std::llround(1e9 / max_hz)) : 0) {}

bool RateLimiter::admit(int64_t now_ns) {
  if (period_ns_ == 0) return true;
  if (next_ns_ != INT64_MIN && now_ns < next_ns_) {
    ++dropped_;
    return false;
  }
  // A sample a little late keeps the cadence; one after a pause restarts it from now.
  next_ns_ = (next_ns_ != INT64_MIN && now_ns - next_ns_ < period_ns_) ? next_ns_ + period_ns_
                                                                         : now_ns + period_ns_;
  return true;
}

RateMeter::RateMeter(int64_t window_ns) : window_ns_(window_ns) {}

void RateMeter::add(int64_t now_ns) {
  const size_t tail = (head_ + size_) % kCapacity;
  times_[tail] = now_ns;
  if (size_ < kCapacity) {
    ++size_;
  } else {
    head_ = (head_ + 1) % kCapacity;
  }
  ++count_;
  last_ns_ = now_ns;
}

double RateMeter::hz(int64_t now_ns) const {
  // Samples inside (now - window, now]; the rate is (n - 1) over their span, as `topic hz` does.
  size_t first = 0;
  while (first < size_ && times_[(head_ + first) % kCapacity] <= now_ns - window_ns_) ++first;
  const size_t n = size_ - first;
  if (n < 2) return 0.0;
  const int64_t t0 = times_[(head_ + first) % kCapacity];
  const int64_t t1 = times_[(head_ + size_ - 1) % kCapacity];
  if (t1 <= t0) return 0.0;
  return static_cast<double>(n - 1) * 1e9 / static_cast<double>(t1 - t0);
}

}  // namespace concert::gui
