#include "modelgen/service.hpp"

#include "modelgen/bundle.hpp"

namespace concert::modelgen {

namespace {

ModelVersioner versioner_for(const ServiceParams& p) {
  if (!p.bundle_dir) return ModelVersioner();
  const auto [version, hash] = read_bundle_version(*p.bundle_dir);
  return ModelVersioner::resume(version, hash);
}

}  // namespace

ModelgenService::ModelgenService(const module_db::ModuleDatabase& db, ServiceParams params)
    : db_(db), params_(std::move(params)), generator_(db_, params_.generator), versioner_(versioner_for(params_)) {}

Outcome ModelgenService::offer(GeneratedModel model) {
  const ModelVersioner::Update u = versioner_.offer(std::move(model));
  Outcome out{u.published, u.version, {}};
  if (u.published && params_.bundle_dir) {
    try {
      if (read_bundle_version(*params_.bundle_dir).second != versioner_.current()->content_hash) {
        write_bundle(*versioner_.current(), *params_.bundle_dir);
      }
    } catch (const ModelError& e) {
      out.error = std::string("model published but bundle not written: ") + e.what();
    }
  }
  return out;
}

Outcome ModelgenService::on_tree(const topology::ModuleTree& tree, uint64_t tree_version) {
  const uint64_t current = versioner_.current() ? versioner_.current()->version : 0;
  GeneratedModel model;
  try {
    model = generator_.generate(tree, custom_, tree_version);
  } catch (const ModelError& e) {
    // A customisation that does not fit the new robot (e.g. a homed joint that is gone) is
    // dropped rather than blocking the new tree.
    if (custom_ == Customisation{}) return {false, current, std::string("tree ") + std::to_string(tree_version) + ": " + e.what()};
    try {
      model = generator_.generate(tree, {}, tree_version);
    } catch (const ModelError& e2) {
      return {false, current, std::string("tree ") + std::to_string(tree_version) + ": " + e2.what()};
    }
    custom_ = {};
  }
  tree_ = tree;
  tree_version_ = tree_version;
  return offer(std::move(model));
}

Outcome ModelgenService::on_customisation(const CustomisationRequest& request) {
  const uint64_t current = versioner_.current() ? versioner_.current()->version : 0;
  const std::string who = "customisation request " + std::to_string(request.request_id);
  if (!tree_) return {false, current, who + ": no module tree yet"};
  if (request.base_version != 0 && request.base_version != current) {
    return {false, current,
            who + ": made for model version " + std::to_string(request.base_version) + " but the current version is " + std::to_string(current)};
  }
  try {
    GeneratedModel model = generator_.generate(*tree_, request.customisation, tree_version_);
    custom_ = request.customisation;
    return offer(std::move(model));
  } catch (const ModelError& e) {
    return {false, current, who + ": " + e.what()};
  }
}

}  // namespace concert::modelgen
