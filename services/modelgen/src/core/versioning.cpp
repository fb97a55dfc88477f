#include "modelgen/versioning.hpp"

#include <algorithm>

namespace concert::modelgen {

ModelVersioner ModelVersioner::resume(uint64_t version, std::string hash) {
  ModelVersioner v(version + 1);
  v.resumed_version_ = version;
  v.resumed_hash_ = std::move(hash);
  return v;
}

void ModelVersioner::learn(uint64_t version, const std::string& hash) {
  if (version == 0 || version <= known_version()) return;
  next_version_ = std::max(next_version_, version + 1);
  if (!current_) {
    resumed_version_ = version;
    resumed_hash_ = hash;
  }
}

uint64_t ModelVersioner::known_version() const {
  return std::max(current_ ? current_->version : 0, std::max(resumed_version_, next_version_ - 1));
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
