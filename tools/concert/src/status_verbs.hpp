#pragma once
#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"

namespace concert::tool {

/// The last status of one service instance, as read from concert/system/status.
struct ServiceRow {
  std::string service;
  std::string host;
  std::string state;        ///< "starting", "ready", "reconfiguring", "error", "stopped"
  uint32_t model_version = 0;
  std::string message;
  double age_s = 0;         ///< seconds since the service last reported (heartbeat)
};

/// Statuses seen on the domain within `wait`, sorted by service then host.
std::vector<ServiceRow> read_statuses(int32_t domain, std::chrono::milliseconds wait);

/// Registers `concert status`.
void register_status_verb(cli::Cli& concert);

}  // namespace concert::tool
