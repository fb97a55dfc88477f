#pragma once
// Publishes one service's ServiceStatus (state, model version, last message) on the status
// topic; every service has one. The instance key is derived from service and host.

#include <mutex>
#include <string>

#include "concert/dds/endpoint.hpp"

namespace concert::dds {

/// This machine's host name (or "unknown").
std::string host_name();

class StatusReporter {
 public:
  StatusReporter(Participant& participant, std::string service, std::string host = host_name());
  /// Reports SERVICE_STOPPED, so that tools show a clean stop rather than a silent one.
  ~StatusReporter();

  void report(msg::ServiceState state, uint32_t model_version, const std::string& message);
  /// Same state and version as last time, new message (e.g. an error that kept the old state).
  void note(const std::string& message);

  msg::ServiceState state() const;
  uint32_t model_version() const;

 private:
  Writer<msg::ServiceStatus> writer_;
  mutable std::mutex mutex_;
  msg::ServiceStatus status_;
};

}  // namespace concert::dds
