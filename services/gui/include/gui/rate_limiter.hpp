#pragma once
// Per-client rate limiting of sensor streams: a tablet on Wi-Fi gets at most `max_hz` samples a
// second of a stream, the newest ones (samples between are dropped, never queued).

#include <cstddef>
#include <cstdint>

namespace concert::gui {

class RateLimiter {
 public:
  /// `max_hz` <= 0: no limit.
  explicit RateLimiter(double max_hz = 0.0);

  /// True when a sample arriving at `now_ns` [ns] may be sent (and counts it as sent): at least
  /// 1/max_hz after the last one sent. Late samples do not accumulate credit.
  bool admit(int64_t now_ns);

  double max_hz() const { return max_hz_; }
  uint64_t dropped() const { return dropped_; }

 private:
  double max_hz_;
  int64_t period_ns_;
  int64_t next_ns_ = INT64_MIN;
  uint64_t dropped_ = 0;
};

/// Samples per second of one topic over a sliding window (what `concert topic hz` shows).
class RateMeter {
 public:
  explicit RateMeter(int64_t window_ns = 2'000'000'000);
  void add(int64_t now_ns);
  /// Rate [Hz] over the window ending at `now_ns`; 0 with fewer than 2 samples in it.
  double hz(int64_t now_ns) const;
  uint64_t count() const { return count_; }
  int64_t last_ns() const { return last_ns_; }

 private:
  int64_t window_ns_;
  // Ring of arrival times within the window (bounded: a 1 kHz stream over 2 s is 2000 entries).
  static constexpr size_t kCapacity = 4096;
  int64_t times_[kCapacity] = {};
  size_t head_ = 0, size_ = 0;
  uint64_t count_ = 0;
  int64_t last_ns_ = 0;
};

}  // namespace concert::gui
