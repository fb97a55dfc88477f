#include "modelgen/versioning.hpp"

namespace concert::modelgen {

ModelVersioner::Update ModelVersioner::offer(RobotModel model) {
  if (current_ && current_->content_hash == model.content_hash) {
    current_->tree_version = model.tree_version;
    return {false, current_->version};
  }
  model.version = next_version_++;
  current_ = std::move(model);
  return {true, current_->version};
}

}  // namespace concert::modelgen
