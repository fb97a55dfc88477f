#pragma once
// What the discovery service does with each scan, without any middleware: keep the last good
// tree and its version; a faulty scan never replaces it.

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>

#include "concert/topology/reconstruction.hpp"

namespace concert::discovery {

/// Result of one scan.
struct ScanOutcome {
  enum class Kind {
    kPublished,  ///< a new tree (new version): publish it
    kUnchanged,  ///< same tree as the current one: nothing to publish
    kRejected,   ///< faulty scan: the current tree stays; `message` says why
  };
  Kind kind = Kind::kRejected;
  uint32_t version = 0;  ///< version of the current tree after this scan; 0 = none yet
  std::string message;   ///< one line for the service status and the log
};

/// Scan -> versioned tree. Not thread-safe: call from one thread.
class DiscoveryService {
 public:
  explicit DiscoveryService(topology::Discovery discovery) : discovery_(std::move(discovery)) {}

  /// Rebuilds the tree from `scan` (scan_id names it in messages). Never throws for a bad
  /// scan: the error is in the outcome.
  ScanOutcome on_scan(const topology::EscScan& scan, uint32_t scan_id);

  /// A restarted service continues the versions of its previous incarnation: its next tree is
  /// numbered after `version` (the newest the wire names: the tree the running model was
  /// generated from), so tree versions never go back or repeat. The tree's own latched sample
  /// died with the previous process, so a tree equal to it gets the next version too.
  void continue_after(uint32_t version) { resumed_after_ = std::max(resumed_after_, version); }

  /// The last good tree, if any.
  const std::optional<topology::ModuleTree>& tree() const { return tree_; }
  /// Its version: 1 for the first tree, +1 for every different tree; 0 = none yet.
  uint32_t version() const { return version_; }
  /// scan_id of the scan the current tree came from.
  uint32_t tree_scan_id() const { return tree_scan_id_; }

 private:
  topology::Discovery discovery_;
  std::optional<topology::ModuleTree> tree_;
  uint32_t version_ = 0;
  uint32_t resumed_after_ = 0;
  uint32_t tree_scan_id_ = 0;
};

}  // namespace concert::discovery
