#include "discovery_node.hpp"

#include <memory>
#include <optional>

#include "concert/common/clock.hpp"
#include "concert/topology/dds/conversions.hpp"

namespace concert::discovery::dds {
DiscoveryNode::DiscoveryNode(concert::dds::Participant& participant, DiscoveryService service,
                             std::ostream& log, std::chrono::milliseconds resume_wait)
    : service_(std::move(service)),
      resume_wait_(resume_wait),
      models_(participant, concert::dds::topics::robot_model),
      statuses_(std::make_unique<concert::dds::Reader<msg::ServiceStatus>>(
          participant, concert::dds::topics::status)),
      scans_(participant, concert::dds::topics::esc_scan),
      trees_(participant, concert::dds::topics::module_tree),
      status_(participant, "discovery"),
      log_(log) {
  status_.report(msg::SERVICE_READY, 0, "no tree yet: waiting for a scan");
}

ScanOutcome DiscoveryNode::handle(const msg::EscScan& scan) {
  ScanOutcome outcome = service_.on_scan(topology::dds::to_core(scan), scan.scan_id());
  const std::string line = "discovery: " + outcome.message;
  switch (outcome.kind) {
    case ScanOutcome::Kind::kPublished:
      if (!trees_.write(topology::dds::to_msg(*service_.tree(), service_.version(), scan.scan_id(),
                                              now_ns()))) {
        status_.report(msg::SERVICE_ERROR, 0,
                       "could not publish tree version " + std::to_string(outcome.version));
        log_ << "discovery: could not publish tree version " << outcome.version << std::endl;
        return outcome;
      }
      status_.report(msg::SERVICE_READY, 0, outcome.message);
      log_ << line << std::endl;
      break;
    case ScanOutcome::Kind::kUnchanged:
      status_.report(msg::SERVICE_READY, 0, outcome.message);
      log_ << line << std::endl;
      break;
    case ScanOutcome::Kind::kRejected:
      status_.report(msg::SERVICE_ERROR, 0, outcome.message);
      status_.refused(outcome.message);
      log_ << line << std::endl;
      break;
  }
  return outcome;
}

void DiscoveryNode::resume_from_wire() {
  resumed_ = true;
  // The other services' statuses (small, latched, every service beats) say whether a model
  // runs: on a fresh stack none does and the wait ends after resume_wait. After a restart the
  // model (large: its URDF) can take longer to arrive than the statuses, and on a loaded
  // machine the other processes' writers can take longer than resume_wait to match at all:
  // the wait goes on while nobody else was heard (up to 3 x resume_wait) and while a model
  // runs that has not arrived (up to 5 x resume_wait).
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  bool heard_others = false;
  bool a_model_runs = false;
  std::optional<msg::RobotModel> model;
  while (!model) {
    while (auto s = statuses_->take()) {
      if (s->service() == "discovery") continue;  // our own
      heard_others = true;
      a_model_runs = a_model_runs || s->model_version() > 0;
    }
    const int bound = a_model_runs ? 5 : heard_others ? 1 : 3;
    if (Clock::now() - start >= bound * resume_wait_) break;
    model = models_.wait(std::chrono::milliseconds(20));
  }
  statuses_.reset();
  if (!model || model->tree_version() == 0) return;
  service_.continue_after(model->tree_version());
  log_ << "discovery: the running model version " << model->version()
       << " was generated from tree version " << model->tree_version()
       << ": trees are numbered after it" << std::endl;
}

int DiscoveryNode::spin_once(std::chrono::milliseconds timeout) {
  if (!resumed_) resume_from_wire();
  int handled = 0;
  if (auto scan = scans_.wait(timeout)) {
    handle(*scan);
    ++handled;
    while (auto more = scans_.take()) {
      handle(*more);
      ++handled;
    }
  }
  return handled;
}

void DiscoveryNode::spin(const std::atomic<bool>& stop, std::chrono::milliseconds poll) {
  while (!stop.load()) spin_once(poll);
}

}  // namespace concert::discovery::dds
