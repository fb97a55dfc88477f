#pragma once
// Publishes one service's ServiceStatus (state, model version, last message) on the status
// topic; every service has one. The instance key is derived from service and host.
//
// Heartbeat: the last status is re-published every `heartbeat` period (new stamp_ns) from a
// background thread, so a service that dies or is cut off from the network goes silent and
// the safety service can tell (liveliness, services/safety). The heartbeat thread runs at
// kHeartbeatNice where permitted.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "concert/dds/endpoint.hpp"

namespace concert::dds {

/// This machine's host name: CONCERT_HOST if set (containers, network namespaces), else the
/// system host name (or "unknown").
std::string host_name();

/// Default heartbeat period of a StatusReporter [ms].
inline constexpr std::chrono::milliseconds kDefaultHeartbeat{200};

/// Nice value of the heartbeat thread, where the process may lower it (CAP_SYS_NICE or
/// RLIMIT_NICE): a loaded PC then starves the service's work before its proof of life.
inline constexpr int kHeartbeatNice = -10;

/// The robot model a service runs: version and content hash (RobotModel.content_hash). Two
/// services at the same version with different hashes disagree (`concert status` flags it).
struct ModelId {
  uint32_t version = 0;  ///< 0 = none yet
  std::string hash;      ///< "" = none or unknown
  bool operator==(const ModelId&) const = default;
};

class StatusReporter {
 public:
  /// `heartbeat`: re-publish period of the status [ms]; zero disables the heartbeat.
  StatusReporter(Participant& participant, std::string service, std::string host = host_name(),
                 std::chrono::milliseconds heartbeat = kDefaultHeartbeat);
  /// Stops the heartbeat and reports SERVICE_STOPPED, so that tools show a clean stop rather
  /// than a silent one.
  ~StatusReporter();
  StatusReporter(const StatusReporter&) = delete;
  StatusReporter& operator=(const StatusReporter&) = delete;

  /// State, the model the service runs, and a message.
  void report(msg::ServiceState state, const ModelId& model, const std::string& message);
  /// Same, for a service that knows only the version: the hash is kept while the version stays
  /// the same, and cleared when it changes.
  void report(msg::ServiceState state, uint32_t model_version, const std::string& message);
  /// Same state and model as last time, new message (e.g. an error that kept the old state).
  void note(const std::string& message);
  /// An input was refused (a model, command, request or scan): counts it in `refusals` and
  /// notes `message`, state and model unchanged.
  void refused(const std::string& message);

  msg::ServiceState state() const;
  uint32_t model_version() const;
  ModelId model() const;
  /// Inputs refused since the start.
  uint32_t refusals() const;
  std::chrono::milliseconds heartbeat() const { return heartbeat_; }

 private:
  void beat();

  Writer<msg::ServiceStatus> writer_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  msg::ServiceStatus status_;
  std::chrono::milliseconds heartbeat_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace concert::dds
