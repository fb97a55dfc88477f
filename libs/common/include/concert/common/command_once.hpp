#pragma once
// Commands on a volatile DDS topic may arrive twice: a client that has not heard the service's
// answer writes its command again (concert/common/resend.hpp), because the first reader its
// writer matched may have been another tool's (the GUI's gateway, a recorder) and the sample
// went to that one alone. A service takes each command once, by the client's (id, stamp).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>

namespace concert {

/// The last `capacity` command keys seen. Not thread-safe: the caller serialises.
class CommandOnce {
 public:
  explicit CommandOnce(std::size_t capacity = 64) : capacity_(capacity < 1 ? 1 : capacity) {}

  /// True the first time (id, stamp) is seen (and remembers it); false for a repetition.
  bool first_time(std::uint64_t id, std::int64_t stamp_ns) {
    const std::pair<std::uint64_t, std::int64_t> key{id, stamp_ns};
    if (std::find(seen_.begin(), seen_.end(), key) != seen_.end()) return false;
    if (seen_.size() == capacity_) seen_.pop_front();
    seen_.push_back(key);
    return true;
  }

 private:
  std::size_t capacity_;
  std::deque<std::pair<std::uint64_t, std::int64_t>> seen_;
};

}  // namespace concert
