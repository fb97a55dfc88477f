#include "discovery/service.hpp"

namespace concert::discovery {
namespace {

using Severity = topology::TreeIssue::Severity;

/// "first issue of that severity (and N more)".
std::string summary(const topology::ModuleTree& tree, Severity severity) {
  std::string first;
  std::size_t count = 0;
  for (const auto& issue : tree.issues) {
    if (issue.severity != severity) continue;
    if (count++ == 0) first = issue.text();
  }
  if (count > 1) first += " (and " + std::to_string(count - 1) + " more)";
  return first;
}

}  // namespace

ScanOutcome DiscoveryService::on_scan(const topology::EscScan& scan, uint32_t scan_id) {
  ScanOutcome outcome;
  const std::string scan_name = "scan " + std::to_string(scan_id);
  topology::ModuleTree tree = discovery_.rebuild(scan);
  if (tree.has_errors()) {
    outcome.kind = ScanOutcome::Kind::kRejected;
    outcome.version = version_;
    outcome.message = scan_name + " rejected: " + summary(tree, Severity::kError) +
                      (version_ > 0 ? " (keeping tree version " + std::to_string(version_) + ")"
                                    : " (no tree yet)");
    return outcome;
  }
  std::string size = std::to_string(tree.modules.size()) + " modules, " +
                     std::to_string(tree.slaves.size()) + " slaves";
  if (const auto unknown = tree.unknown_modules(); !unknown.empty()) {
    size += ", " + std::to_string(unknown.size()) + " unknown";
  }
  if (const auto warnings = tree.count(Severity::kWarning); warnings > 0) {
    size += "; " + std::to_string(warnings) + " warning" + (warnings == 1 ? "" : "s") + ": " +
            summary(tree, Severity::kWarning);
  }
  if (tree_ && *tree_ == tree) {
    outcome.kind = ScanOutcome::Kind::kUnchanged;
    outcome.version = version_;
    outcome.message =
        scan_name + ": tree unchanged (version " + std::to_string(version_) + ", " + size + ")";
    return outcome;
  }
  tree_ = std::move(tree);
  version_ = std::max(version_, resumed_after_) + 1;
  tree_scan_id_ = scan_id;
  outcome.kind = ScanOutcome::Kind::kPublished;
  outcome.version = version_;
  outcome.message = scan_name + ": tree version " + std::to_string(version_) + " (" + size + ")";
  return outcome;
}

}  // namespace concert::discovery
