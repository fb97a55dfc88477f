#pragma once
// Versioning of published models: versions strictly increase, unchanged content (same hash)
// gives no new version, and a failed generation never replaces the current model.

#include <cstdint>
#include <optional>
#include <string>

#include "modelgen/model_generator.hpp"

namespace concert::modelgen {

class ModelVersioner {
 public:
  /// Outcome of offering a newly generated model.
  struct Update {
    bool published = false;  ///< true: the model became current with a new version
    uint64_t version = 0;    ///< version of the current model after the call
  };

  /// `first_version` is the version given to the first model (e.g. one more than the last version
  /// read back from a bundle on disk, so versions keep increasing across restarts).
  explicit ModelVersioner(uint64_t first_version = 1) : next_version_(first_version == 0 ? 1 : first_version) {}

  /// Resumes after a restart from the last published version and hash (e.g. a bundle manifest):
  /// the next different model gets `version + 1`; a first model with hash `hash` keeps `version`.
  static ModelVersioner resume(uint64_t version, std::string hash);

  /// A model (`version`, `hash`) is known to exist elsewhere (the services on the wire run it, or
  /// a bundle on disk holds it): versions are never reused for other content, so the next
  /// different model gets at least `version + 1`, and, before any model is current here, a
  /// model with `hash` takes `version` again. Lower or equal knowledge changes nothing.
  void learn(uint64_t version, const std::string& hash);

  /// Makes `model` current with the next version unless its content hash equals the current
  /// model's (then only tree_version is refreshed and nothing is published).
  Update offer(GeneratedModel model);

  /// The highest version known (current, learned or resumed); 0 = none.
  uint64_t known_version() const;

  /// The current model, if any.
  const std::optional<GeneratedModel>& current() const { return current_; }

 private:
  uint64_t next_version_;
  uint64_t resumed_version_ = 0;
  std::string resumed_hash_;
  std::optional<GeneratedModel> current_;
};

}  // namespace concert::modelgen
