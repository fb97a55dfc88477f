#include "modelgen/versioning.hpp"

namespace concert::modelgen {

ModelVersioner ModelVersioner::resume(uint64_t version, std::string hash) {
  ModelVersioner v(version + 1);
  v.resumed_version_ = version;
  v.resumed_hash_ = std::move(hash);
  return v;
}

ModelVersioner::Update ModelVersioner::offer(GeneratedModel model) {
  if (!current_ && resumed_version_ > 0 && model.content_hash == resumed_hash_) {
    model.version = resumed_version_;
    current_ = std::move(model);
    return {true, current_->version};
  }
  if (current_ && current_->content_hash == model.content_hash) {
    current_->tree_version = model.tree_version;
    return {false, current_->version};
  }
  model.version = next_version_++;
  current_ = std::move(model);
  return {true, current_->version};
}

}  // namespace concert::modelgen
