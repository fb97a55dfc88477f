#pragma once
#include <chrono>
#include <cstdint>
#include <optional>
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
  std::string model_hash;  ///< content hash of that model; "" = none or unknown
  uint32_t refusals = 0;   ///< inputs the service refused since it started
  std::string message;
  double age_s = 0;         ///< seconds since the service last reported (heartbeat)
};

/// The safety layer's state, as read from concert/safety/state (latched).
struct SafetyRow {
  bool stopped = false;
  std::vector<std::string> causes;
};

/// Statuses seen on the domain within `wait`, sorted by service then host; with `safety`, also
/// the safety state heard meanwhile (nullopt: none).
std::vector<ServiceRow> read_statuses(int32_t domain, std::chrono::milliseconds wait,
                                      std::optional<SafetyRow>* safety = nullptr);

/// Which model the services run, and who disagrees: the newest (version, hash) any service
/// reports is the reference; a service at another version, or at that version with another
/// hash, disagrees (services that run no model yet are left out).
struct ModelAgreement {
  uint32_t version = 0;                  ///< the reference version; 0 = no service runs a model
  std::string hash;                      ///< its hash ("" if no service reported one)
  std::vector<std::string> disagreeing;  ///< "service@host runs N (hash)"
};
ModelAgreement model_agreement(const std::vector<ServiceRow>& rows);

/// What a scripted check (`concert status --check`) fails on: every service stopped or in
/// error, a model disagreement, and every service that refused inputs. Empty = all good.
std::vector<std::string> status_problems(const std::vector<ServiceRow>& rows);
/// What `concert status --check` fails on besides: the safety layer STOPPED (naming its
/// causes) or not heard at all. A stack that cannot move is not ready to work.
std::vector<std::string> safety_problems(const std::optional<SafetyRow>& safety);

/// Registers `concert status` ([--json] [--check] [--until-version N] [--services a,b]).
void register_status_verb(cli::Cli& concert);

}  // namespace concert::tool
