#pragma once
// DDS adapter of the discovery service: scan topic in, module tree (versioned, latched) and
// service status out. A faulty scan never replaces the last good tree: its error goes into
// the status and to the log.

#include <atomic>
#include <chrono>
#include <memory>
#include <ostream>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "discovery/service.hpp"

namespace concert::discovery::dds {

class DiscoveryNode {
 public:
  /// Creates the reader, writer and status reporter on `participant` (which must outlive the
  /// node) and reports the service READY, waiting for a scan. `log` gets one line per scan.
  /// Before the first scan, spin_once() listens up to `resume_wait` for the robot model on the
  /// wire (latched; longer when the services' statuses say one runs): a restarted discovery
  /// numbers its trees after the tree that model was generated from
  /// (DiscoveryService::continue_after).
  DiscoveryNode(concert::dds::Participant& participant, DiscoveryService service,
                std::ostream& log,
                std::chrono::milliseconds resume_wait = std::chrono::milliseconds(1000));

  /// Handles one scan sample: rebuild, publish a new tree version or report the error.
  ScanOutcome handle(const msg::EscScan& scan);

  /// Waits up to `timeout` for scans and handles every one that arrived; returns how many.
  int spin_once(std::chrono::milliseconds timeout);

  /// Handles scans until `stop` becomes true (checked every `poll`).
  void spin(const std::atomic<bool>& stop,
            std::chrono::milliseconds poll = std::chrono::milliseconds(100));

  const DiscoveryService& service() const { return service_; }

 private:
  void resume_from_wire();

  DiscoveryService service_;
  std::chrono::milliseconds resume_wait_;
  bool resumed_ = false;
  concert::dds::Reader<msg::RobotModel> models_;
  std::unique_ptr<concert::dds::Reader<msg::ServiceStatus>> statuses_;  // until resumed
  concert::dds::Reader<msg::EscScan> scans_;
  concert::dds::Writer<msg::ModuleTree> trees_;
  concert::dds::StatusReporter status_;
  std::ostream& log_;
};

}  // namespace concert::discovery::dds
