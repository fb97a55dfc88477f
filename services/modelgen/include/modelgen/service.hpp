#pragma once
// The modelgen service logic without middleware: module trees and customisation requests in,
// versioned models out. A tree or request that cannot be modelled leaves the current model in
// place and is reported as an error.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "concert/module_db/module_db.hpp"
#include "concert/topology/types.hpp"
#include "modelgen/model_generator.hpp"
#include "modelgen/versioning.hpp"

namespace concert::modelgen {

/// A customisation request (section 4.4), as carried by the customisation topic.
struct CustomisationRequest {
  uint64_t request_id = 0;
  uint64_t base_version = 0;  ///< model version it was made against; 0 = any
  Customisation customisation;  ///< replaces the current customisation as a whole
};

/// What one input did.
struct Outcome {
  bool published = false;  ///< a new model version became current
  uint64_t version = 0;    ///< current model version afterwards (0 = none)
  std::string error;       ///< empty on success
};

struct ServiceParams {
  Params generator;
  /// When set, every published model is also written there as a bundle, and versions continue
  /// from its manifest (the same content keeps its version across restarts).
  std::optional<std::filesystem::path> bundle_dir;
};

class ModelgenService {
 public:
  /// The database must outlive the service.
  ModelgenService(const module_db::ModuleDatabase& db, ServiceParams params = {});

  /// A new module tree (tree_version = ModuleTree.version on the wire).
  Outcome on_tree(const topology::ModuleTree& tree, uint64_t tree_version);

  /// A customisation request; needs a tree. Refused when base_version is set and differs from
  /// the current model version.
  Outcome on_customisation(const CustomisationRequest& request);

  /// A model that the services on the wire run (read from their status after a restart): see
  /// ModelVersioner::learn. Call before the first tree, so that a restarted modelgen gives the
  /// running model its version again and never reuses a version for other content.
  void learn(uint64_t version, const std::string& hash) { versioner_.learn(version, hash); }

  /// The current model, if any.
  const std::optional<GeneratedModel>& current() const { return versioner_.current(); }
  /// The highest model version known (current, learned from the wire or the bundle).
  uint64_t known_version() const { return versioner_.known_version(); }
  const Customisation& customisation() const { return custom_; }
  const ServiceParams& params() const { return params_; }

 private:
  Outcome offer(GeneratedModel model);

  const module_db::ModuleDatabase& db_;
  ServiceParams params_;
  ModelGenerator generator_;
  ModelVersioner versioner_;
  std::optional<topology::ModuleTree> tree_;
  uint64_t tree_version_ = 0;
  Customisation custom_;
};

}  // namespace concert::modelgen
