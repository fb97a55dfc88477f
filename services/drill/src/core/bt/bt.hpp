#pragma once
// A minimal behaviour-tree engine for the drilling mission (paper Fig. 11).
//
// Why not BehaviorTree.CPP: it is not packaged for Debian 12 and we install Debian packages
// only. The mission needs little of it, so this is the small subset it uses, kept readable:
//
//   Sequence   runs its children in order; fails with the first that fails. With memory: a
//              child that finished is not ticked again until the sequence itself finishes.
//   Fallback   runs its children in order until one succeeds; fails when all failed. With memory.
//   Action     starts an operation on its first tick, then polls it until it is done.
//   Condition  a test: succeeds or fails in the tick it is asked.
//   ForEach    runs its body once per item (the list is taken when the loop starts); a failed
//              item is reported to the loop's owner and the loop goes on with the next item.
//   Finally    runs its body, then its cleanup whatever the body's result (try/finally).
//
// tick() returns kRunning, kSuccess or kFailure. A node that finishes (kSuccess or kFailure) is
// back in its initial state, so a loop's body runs afresh for the next item. A failure carries
// its reason up the tree ("drill: bit stalled"), as an exception would. There is no halting:
// the owner of a tree stops ticking it to abandon it. Single-threaded, like every tick.

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drill/ports.hpp"

namespace concert::drill::bt {

enum class Status { kRunning, kSuccess, kFailure };

class Node {
 public:
  explicit Node(std::string name) : name_(std::move(name)) {}
  virtual ~Node() = default;
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  /// Advances the node by one step.
  Status tick();

  const std::string& name() const { return name_; }
  /// Why the node's last run failed ("" if it did not).
  const std::string& failure() const { return failure_; }
  /// Whether the last tick returned kRunning.
  bool running() const { return running_; }

  /// The node's part of the active path: its name (a loop: its current item's label).
  virtual std::string label() const { return name_; }
  /// Leaves the node out of active paths (a grouping node that says nothing a user needs).
  Node& hide_in_path() {
    in_path_ = false;
    return *this;
  }
  bool in_path() const { return in_path_; }
  /// The child that is running now, if any.
  virtual const Node* running_child() const { return nullptr; }
  /// "sequence", "action", ...
  virtual const char* kind() const = 0;
  /// Appends the subtree's shape, one node a line ("  name (kind)"), indented by depth.
  void describe(std::string& out, int depth = 0) const;

 protected:
  virtual Status on_tick() = 0;
  /// Back to the initial state, after the node finished.
  virtual void reset() {}
  virtual std::vector<const Node*> children() const { return {}; }
  /// Records why the node fails; returns kFailure.
  Status fail(std::string why);

 private:
  std::string name_;
  std::string failure_;
  bool running_{false};
  bool in_path_{true};
};

using NodePtr = std::unique_ptr<Node>;

/// The labels of the running nodes from `root` down, joined by '/' ("" when nothing runs).
std::string active_path(const Node& root);

/// Base of Sequence and Fallback: children ticked in order, from the one that last ran.
class Composite : public Node {
 public:
  Composite(std::string name, std::vector<NodePtr> children);
  const Node* running_child() const override;

 protected:
  /// Ticks children from the current one while they end with `go_on`; returns the status of the
  /// child that did not, or `exhausted` when every child did.
  Status tick_children(Status go_on, Status exhausted);
  void reset() override { current_ = 0; }
  std::vector<const Node*> children() const override;

 private:
  std::vector<NodePtr> children_;
  std::size_t current_{0};
};

class Sequence : public Composite {
 public:
  using Composite::Composite;
  const char* kind() const override { return "sequence"; }

 protected:
  Status on_tick() override { return tick_children(Status::kSuccess, Status::kSuccess); }
};

class Fallback : public Composite {
 public:
  using Composite::Composite;
  const char* kind() const override { return "fallback"; }

 protected:
  Status on_tick() override { return tick_children(Status::kFailure, Status::kFailure); }
};

/// An operation of the robot: `start` is called on the first tick, `poll` on every tick from
/// that one on, until it reports success or failure. A failure reads "NAME: REASON".
class Action : public Node {
 public:
  Action(std::string name, std::function<void()> start, std::function<Outcome()> poll)
      : Node(std::move(name)), start_(std::move(start)), poll_(std::move(poll)) {}
  const char* kind() const override { return "action"; }

 protected:
  Status on_tick() override;
  void reset() override { started_ = false; }

 private:
  std::function<void()> start_;
  std::function<Outcome()> poll_;
  bool started_{false};
};

/// A test, decided in the tick it is asked; a failure reads "NAME: no".
class Condition : public Node {
 public:
  Condition(std::string name, std::function<bool()> test)
      : Node(std::move(name)), test_(std::move(test)) {}
  const char* kind() const override { return "condition"; }

 protected:
  Status on_tick() override;

 private:
  std::function<bool()> test_;
};

/// Runs `body` once per item of `items()` (called when the loop starts). `begin(item)` is called
/// before an item's first tick, `end(item, status, failure)` when its body finished; it returns
/// whether the loop goes on. A failed item does not stop the loop unless `end` says so: then the
/// loop fails with "LABEL: FAILURE". The loop succeeds when every item was run.
class ForEach : public Node {
 public:
  struct Hooks {
    std::function<std::vector<std::size_t>()> items;
    std::function<std::string(std::size_t)> label;  ///< the active path's part for an item
    std::function<void(std::size_t)> begin;
    std::function<bool(std::size_t, Status, const std::string&)> end;
  };
  ForEach(std::string name, Hooks hooks, NodePtr body);
  const char* kind() const override { return "for each"; }
  std::string label() const override;
  const Node* running_child() const override;

 protected:
  Status on_tick() override;
  void reset() override;
  std::vector<const Node*> children() const override { return {body_.get()}; }

 private:
  Hooks hooks_;
  NodePtr body_;
  std::vector<std::size_t> items_;
  std::size_t next_{0};  ///< index in items_ of the item running or to run
  bool started_{false};
  bool item_begun_{false};
};

/// Runs `body` to its end, then `cleanup` to its end, whatever the body's result. Fails with the
/// body's failure if it failed, else with the cleanup's.
class Finally : public Node {
 public:
  Finally(std::string name, NodePtr body, NodePtr cleanup);
  const char* kind() const override { return "finally"; }
  const Node* running_child() const override;

 protected:
  Status on_tick() override;
  void reset() override;
  std::vector<const Node*> children() const override { return {body_.get(), cleanup_.get()}; }

 private:
  NodePtr body_;
  NodePtr cleanup_;
  bool body_done_{false};
  Status body_status_{Status::kSuccess};
  std::string body_failure_;
};

/// Helpers to write a tree as nested calls.
template <class... Children>
std::vector<NodePtr> nodes(Children&&... children) {
  std::vector<NodePtr> out;
  (out.push_back(std::forward<Children>(children)), ...);
  return out;
}
template <class... Children>
NodePtr sequence(std::string name, Children&&... children) {
  return std::make_unique<Sequence>(std::move(name), nodes(std::forward<Children>(children)...));
}
template <class... Children>
NodePtr fallback(std::string name, Children&&... children) {
  return std::make_unique<Fallback>(std::move(name), nodes(std::forward<Children>(children)...));
}
/// The node, left out of active paths.
inline NodePtr hidden(NodePtr node) {
  node->hide_in_path();
  return node;
}

}  // namespace concert::drill::bt
