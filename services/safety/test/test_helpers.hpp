#pragma once
// Helpers shared by the safety service's DDS tests (in-process adapter and real process).

#include <chrono>
#include <functional>

#include "concert/dds/endpoint.hpp"
#include "system.h"

namespace concert::safety {

using concert::dds::Participant;
using concert::dds::Reader;
using concert::dds::Writer;
namespace topics = concert::dds::topics;

}  // namespace concert::safety

namespace concert::safety::test {

/// Reads SafetyState samples from `reader` until one satisfies `pred`; false if none did
/// within `timeout`.
inline bool wait_state(Reader<msg::SafetyState>& reader,
                       const std::function<bool(const msg::SafetyState&)>& pred,
                       std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = reader.wait(std::chrono::milliseconds(100)); s && pred(*s)) return true;
  }
  return false;
}

}  // namespace concert::safety::test
