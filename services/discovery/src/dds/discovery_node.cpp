#include "discovery_node.hpp"

#include "concert/topology/dds/conversions.hpp"

namespace concert::discovery::dds {
namespace {

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

DiscoveryNode::DiscoveryNode(concert::dds::Participant& participant, DiscoveryService service,
                             std::ostream& log)
    : service_(std::move(service)),
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

int DiscoveryNode::spin_once(std::chrono::milliseconds timeout) {
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
