#pragma once
// The simulator's command channel for the command line (`concert sim ...`).

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "concert/dds/topics.hpp"

namespace concert::tool {

/// The simulator's command channel (SimCommand out, SimCommandReply in) on one domain, for
/// several commands in a row.
class SimChannel {
 public:
  explicit SimChannel(std::int32_t domain);
  ~SimChannel();
  SimChannel(const SimChannel&) = delete;
  SimChannel& operator=(const SimChannel&) = delete;
  [[nodiscard]] std::int32_t domain() const;
  /// Sends a command and returns the simulator's reply (accepted or refused); resent every
  /// second until it comes. Throws Failure when no simulator listens or none answers within
  /// `timeout`.
  msg::SimCommandReply send(msg::SimCommandKind kind, const std::string& name, const std::string& content,
                            std::chrono::milliseconds timeout);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::tool
