#pragma once
// DDS adapter of the modelgen service: module tree and customisation requests in, GeneratedModel
// (transient-local, latched) and service status out. Errors keep the current model; they go to
// the status message and the log.

#include <atomic>
#include <chrono>
#include <ostream>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "modelgen/service.hpp"

namespace concert::modelgen::dds {

class ModelgenNode {
 public:
  /// `participant` and `service` must outlive the node. Reports STARTING at once; the first
  /// spin learns which model the services on the wire run (up to `resume_wait`), then READY.
  ModelgenNode(concert::dds::Participant& participant, ModelgenService& service, std::ostream& log,
               std::chrono::milliseconds resume_wait = std::chrono::milliseconds(1000));

  /// Reads the status of the services on the domain for up to `resume_wait` and tells the
  /// service the newest model they run (version and hash): a restarted modelgen then gives
  /// the running model its version again, and never reuses a version for other content. While
  /// no other service that runs models was heard the wait goes on, up to 3 x `resume_wait`: a
  /// modelgen running alone simply waits that long once. Called by the first spin_once.
  void resume_from_wire();

  /// Handles one tree sample: generate, publish a new version or report the error.
  Outcome handle(const msg::ModuleTree& tree);
  /// Handles one customisation request.
  Outcome handle(const msg::ModelCustomisation& request);

  /// Waits up to `timeout` for input and handles everything that arrived; returns how many.
  int spin_once(std::chrono::milliseconds timeout);
  /// Handles input until `stop` becomes true (checked every `poll`).
  void spin(const std::atomic<bool>& stop, std::chrono::milliseconds poll = std::chrono::milliseconds(50));

 private:
  void report(const Outcome& outcome, const std::string& what);
  concert::dds::ModelId current_id() const;

  ModelgenService& service_;
  std::chrono::milliseconds resume_wait_;
  bool resumed_ = false;
  concert::dds::Reader<msg::ServiceStatus> statuses_;
  concert::dds::Reader<msg::ModuleTree> trees_;
  concert::dds::Reader<msg::ModelCustomisation> requests_;
  concert::dds::Writer<msg::RobotModel> models_;
  concert::dds::StatusReporter status_;
  std::ostream& log_;
};

}  // namespace concert::modelgen::dds
