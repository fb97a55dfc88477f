// The small behaviour-tree engine the drilling mission's tree is built from.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bt/bt.hpp"

namespace concert::drill {
namespace {

using ::testing::ElementsAre;

// An action that runs `ticks` ticks, then ends with `result`; counts its starts and polls.
struct Counted {
  int starts{0};
  int polls{0};
};
bt::NodePtr counted(const std::string& name, Counted& c, int ticks, bool succeed = true) {
  return std::make_unique<bt::Action>(
      name, [&c] { ++c.starts; },
      [&c, ticks, succeed] {
        ++c.polls;
        if (c.polls % (ticks + 1) != 0) return Outcome::running();
        return succeed ? Outcome::succeeded() : Outcome::failed("no luck");
      });
}

TEST(BehaviourTree, SequenceRemembersFinishedChildren) {
  Counted a, b;
  auto seq = bt::sequence("seq", counted("a", a, 0), counted("b", b, 2));
  EXPECT_EQ(seq->tick(), bt::Status::kRunning);
  EXPECT_EQ(seq->tick(), bt::Status::kRunning);
  EXPECT_EQ(seq->tick(), bt::Status::kSuccess);
  EXPECT_EQ(a.polls, 1) << "a finished child is not ticked again";
  EXPECT_EQ(b.starts, 1);
  EXPECT_EQ(b.polls, 3);
  EXPECT_EQ(seq->tick(), bt::Status::kRunning) << "a finished sequence runs afresh";
  EXPECT_EQ(a.starts, 2);
}

TEST(BehaviourTree, SequenceFailsWithTheReasonOfTheChildThatFailed) {
  Counted a, b, c;
  auto seq = bt::sequence("seq", counted("a", a, 0), counted("b", b, 0, false), counted("c", c, 0));
  EXPECT_EQ(seq->tick(), bt::Status::kFailure);
  EXPECT_EQ(seq->failure(), "b: no luck");
  EXPECT_EQ(c.starts, 0);
}

TEST(BehaviourTree, FallbackStopsAtTheFirstSuccess) {
  Counted a, b, c;
  auto fb = bt::fallback("fb", counted("a", a, 0, false), counted("b", b, 1), counted("c", c, 0));
  EXPECT_EQ(fb->tick(), bt::Status::kRunning);
  EXPECT_EQ(fb->tick(), bt::Status::kSuccess);
  EXPECT_EQ(a.polls, 1) << "with memory: a failed child is not ticked again";
  EXPECT_EQ(c.starts, 0);

  Counted d, e;
  auto none = bt::fallback("none", counted("d", d, 0, false), counted("e", e, 0, false));
  EXPECT_EQ(none->tick(), bt::Status::kFailure);
  EXPECT_EQ(none->failure(), "e: no luck");
}

TEST(BehaviourTree, ForEachGoesOnAfterAFailedItemUnlessTold) {
  std::vector<std::string> log;
  std::size_t current = 0;
  auto body = std::make_unique<bt::Action>(
      "work", [] {},
      [&] { return current == 1 ? Outcome::failed("broken") : Outcome::succeeded(); });
  bool go_on = true;
  bt::ForEach loop(
      "items",
      {.items =
           [] {
             return std::vector<std::size_t>{0, 1, 2};
           },
       .label = [](std::size_t i) { return "item " + std::to_string(i); },
       .begin = [&](std::size_t i) { current = i; },
       .end =
           [&](std::size_t i, bt::Status s, const std::string& why) {
             log.push_back(std::to_string(i) + (s == bt::Status::kSuccess ? " ok" : " " + why));
             return s == bt::Status::kSuccess || go_on;
           }},
      std::move(body));
  EXPECT_EQ(loop.tick(), bt::Status::kSuccess);
  EXPECT_THAT(log, ElementsAre("0 ok", "1 work: broken", "2 ok"));

  log.clear();
  go_on = false;
  current = 0;
  EXPECT_EQ(loop.tick(), bt::Status::kFailure);
  EXPECT_EQ(loop.failure(), "item 1: work: broken");
  EXPECT_THAT(log, ElementsAre("0 ok", "1 work: broken"));
}

TEST(BehaviourTree, FinallyRunsTheCleanupAfterAFailureAndKeepsItsReason) {
  Counted body, cleanup;
  bt::Finally f("f", counted("body", body, 0, false), counted("cleanup", cleanup, 1));
  EXPECT_EQ(f.tick(), bt::Status::kRunning);
  EXPECT_EQ(f.tick(), bt::Status::kFailure);
  EXPECT_EQ(f.failure(), "body: no luck");
  EXPECT_EQ(cleanup.starts, 1);

  Counted ok, broken;
  bt::Finally g("g", counted("body", ok, 0), counted("cleanup", broken, 0, false));
  EXPECT_EQ(g.tick(), bt::Status::kFailure);
  EXPECT_EQ(g.failure(), "cleanup: no luck");
}

TEST(BehaviourTree, ActivePathUsesItemLabelsAndLeavesHiddenNodesOut) {
  Counted a;
  auto body = bt::hidden(bt::sequence("group", counted("step", a, 1)));
  auto loop = std::make_unique<bt::ForEach>(
      "loop",
      bt::ForEach::Hooks{.items = [] { return std::vector<std::size_t>{7}; },
                         .label = [](std::size_t i) { return "item " + std::to_string(i); },
                         .begin = [](std::size_t) {},
                         .end = [](std::size_t, bt::Status, const std::string&) { return true; }},
      std::move(body));
  auto root = bt::sequence("root", std::move(loop));
  EXPECT_EQ(bt::active_path(*root), "");
  EXPECT_EQ(root->tick(), bt::Status::kRunning);
  EXPECT_EQ(bt::active_path(*root), "root/item 7/step");
  EXPECT_EQ(root->tick(), bt::Status::kSuccess);
  EXPECT_EQ(bt::active_path(*root), "");
}

}  // namespace
}  // namespace concert::drill
