#include "discovery/service.hpp"

namespace concert::discovery {

ScanOutcome DiscoveryService::on_scan(const topology::EscScan& scan, uint32_t scan_id) {
  ScanOutcome outcome;
  const std::string scan_name = "scan " + std::to_string(scan_id);
  try {
    topology::ModuleTree tree = discovery_.run(scan);
    const std::string size = std::to_string(tree.modules.size()) + " modules, " +
                             std::to_string(tree.slaves.size()) + " slaves";
    if (tree_ && *tree_ == tree) {
      outcome.kind = ScanOutcome::Kind::kUnchanged;
      outcome.version = version_;
      outcome.message = scan_name + ": tree unchanged (version " + std::to_string(version_) +
                        ", " + size + ")";
      return outcome;
    }
    tree_ = std::move(tree);
    ++version_;
    tree_scan_id_ = scan_id;
    outcome.kind = ScanOutcome::Kind::kPublished;
    outcome.version = version_;
    outcome.message = scan_name + ": tree version " + std::to_string(version_) + " (" + size + ")";
  } catch (const DiscoveryError& e) {
    outcome.kind = ScanOutcome::Kind::kRejected;
    outcome.version = version_;
    outcome.message = scan_name + " rejected: " + e.what() +
                      (version_ > 0 ? " (keeping tree version " + std::to_string(version_) + ")"
                                    : " (no tree yet)");
  }
  return outcome;
}

}  // namespace concert::discovery
