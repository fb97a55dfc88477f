#include "bt/bt.hpp"

#include "concert/common/text.hpp"

namespace concert::drill::bt {

Status Node::tick() {
  if (!running_) failure_.clear();
  const Status status = on_tick();
  running_ = status == Status::kRunning;
  if (!running_) reset();
  return status;
}

Status Node::fail(std::string why) {
  failure_ = std::move(why);
  return Status::kFailure;
}

void Node::describe(std::string& out, int depth) const {
  out.append(2 * static_cast<std::size_t>(depth), ' ');
  out += name_ + " (" + kind() + ")\n";
  for (const Node* child : children()) child->describe(out, depth + 1);
}

std::string active_path(const Node& root) {
  std::vector<std::string> parts;
  for (const Node* node = &root; node != nullptr && node->running(); node = node->running_child()) {
    if (node->in_path()) parts.push_back(node->label());
  }
  return join(parts, "/");
}

Composite::Composite(std::string name, std::vector<NodePtr> children)
    : Node(std::move(name)), children_(std::move(children)) {}

const Node* Composite::running_child() const {
  if (current_ < children_.size() && children_[current_]->running()) {
    return children_[current_].get();
  }
  return nullptr;
}

std::vector<const Node*> Composite::children() const {
  std::vector<const Node*> out;
  for (const auto& child : children_) out.push_back(child.get());
  return out;
}

Status Composite::tick_children(Status go_on, Status exhausted) {
  const Node* last = nullptr;
  while (current_ < children_.size()) {
    Node& child = *children_[current_];
    last = &child;
    const Status status = child.tick();
    if (status == Status::kRunning) return status;
    if (status != go_on) {
      return status == Status::kFailure ? fail(child.failure()) : status;
    }
    ++current_;
  }
  if (exhausted == Status::kFailure) return fail(last != nullptr ? last->failure() : "");
  return exhausted;
}

Status Action::on_tick() {
  if (!started_) {
    started_ = true;
    start_();
  }
  Outcome outcome = poll_();
  switch (outcome.progress) {
    case Progress::kRunning:
      return Status::kRunning;
    case Progress::kSucceeded:
      return Status::kSuccess;
    case Progress::kFailed:
      break;
  }
  return fail(name() + ": " + (outcome.reason.empty() ? "failed" : outcome.reason));
}

Status Condition::on_tick() { return test_() ? Status::kSuccess : fail(name() + ": no"); }

ForEach::ForEach(std::string name, Hooks hooks, NodePtr body)
    : Node(std::move(name)), hooks_(std::move(hooks)), body_(std::move(body)) {}

std::string ForEach::label() const {
  if (started_ && next_ < items_.size()) return hooks_.label(items_[next_]);
  return name();
}

const Node* ForEach::running_child() const { return body_->running() ? body_.get() : nullptr; }

Status ForEach::on_tick() {
  if (!started_) {
    started_ = true;
    items_ = hooks_.items();
    next_ = 0;
  }
  while (next_ < items_.size()) {
    const std::size_t item = items_[next_];
    if (!item_begun_) {
      item_begun_ = true;
      hooks_.begin(item);
    }
    const Status status = body_->tick();
    if (status == Status::kRunning) return status;
    item_begun_ = false;
    ++next_;
    if (!hooks_.end(item, status, body_->failure())) {
      return fail(hooks_.label(item) + ": " + body_->failure());
    }
  }
  return Status::kSuccess;
}

void ForEach::reset() {
  started_ = false;
  item_begun_ = false;
  items_.clear();
  next_ = 0;
}

Finally::Finally(std::string name, NodePtr body, NodePtr cleanup)
    : Node(std::move(name)), body_(std::move(body)), cleanup_(std::move(cleanup)) {}

const Node* Finally::running_child() const {
  const Node* child = body_done_ ? cleanup_.get() : body_.get();
  return child->running() ? child : nullptr;
}

Status Finally::on_tick() {
  if (!body_done_) {
    const Status status = body_->tick();
    if (status == Status::kRunning) return status;
    body_done_ = true;
    body_status_ = status;
    body_failure_ = body_->failure();
  }
  const Status cleanup = cleanup_->tick();
  if (cleanup == Status::kRunning) return cleanup;
  if (body_status_ == Status::kFailure) return fail(body_failure_);
  if (cleanup == Status::kFailure) return fail(cleanup_->failure());
  return Status::kSuccess;
}

void Finally::reset() {
  body_done_ = false;
  body_status_ = Status::kSuccess;
  body_failure_.clear();
}

}  // namespace concert::drill::bt
