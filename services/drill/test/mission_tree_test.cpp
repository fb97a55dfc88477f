// The drilling mission's behaviour tree (paper Fig. 11) on a scriptable fake robot: the order of
// the calls (the next area planned while this one is drilled), what a failure at each step does
// to the rest of the mission, health and abort, resuming, the time accounting and the active
// path. First the small behaviour-tree engine it is built from.
#include "drill/mission_tree.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bt/bt.hpp"
#include "concert/common/error_text.hpp"
#include "fake_ports.hpp"

namespace concert::drill {
namespace {

using ::testing::ElementsAre;
using ::testing::ElementsAreArray;
using testing::FakePorts;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;
using testing::run;

// --- the engine ---------------------------------------------------------------------------------

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

// --- the mission --------------------------------------------------------------------------------

// Areas "a0", "a1", ... (the fake decides where they are and what is found in them).
Mission mission_of(std::size_t n) {
  Mission m;
  m.name = "test";
  for (std::size_t i = 0; i < n; ++i) {
    AreaSpec area;
    area.name = "a" + std::to_string(i);
    area.point = Eigen::Vector3d(static_cast<double>(i), 0.0, 1.0);
    m.areas.push_back(area);
  }
  return m;
}

// The calls of drilling both blobs of area `i`, surveyed and the base placed for them first.
std::vector<std::string> holes_of(std::size_t i) {
  std::vector<std::string> out{"survey " + std::to_string(i) + " 2", "place " + std::to_string(i) + " 2"};
  for (const char* blob : {"blob 1", "blob 2"}) {
    const std::string hole = std::to_string(i) + " " + blob;
    out.insert(out.end(), {"align " + hole, "drill " + hole + " 0.050", "retract " + hole});
  }
  return out;
}

std::vector<std::string> concat(std::initializer_list<std::vector<std::string>> parts) {
  std::vector<std::string> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

TEST(MissionTree, ThreeAreasInFigure11Order) {
  FakePorts fake(3);
  fake.areas[1].base = BasePose{1.0, -1.0, 0.5};
  MissionTree tree(mission_of(3), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;

  EXPECT_THAT(fake.calls,
              ElementsAreArray(concat({
                  {"resolve 0", "resolve 1", "resolve 2"},
                  // area 1 has a base pose: it is planned once the base stands there
                  {"plan 0 after none", "execute 0", "detect 0"},
                  holes_of(0),
                  {"navigate 1", "plan 1 after none", "execute 1"},
                  // area 2 is planned from area 1's approach posture while area 1 is drilled
                  {"plan 2 after 1", "detect 1"},
                  holes_of(1),
                  {"execute 2", "detect 2"},
                  holes_of(2),
                  // the arm home at the end: ready to drive or to have its tool swapped
                  {"stow"},
              })));
  EXPECT_LT(fake.index_of("plan 2 after 1"), fake.index_of("drill 1 blob 1 0.050"));
  EXPECT_GT(fake.index_of("execute 2"), fake.index_of("retract 1 blob 2"));
  EXPECT_THAT(fake.violations, IsEmpty());

  const MissionReport& r = tree.report();
  EXPECT_EQ(r.mission, "test");
  EXPECT_EQ(r.holes_drilled(), 6);
  EXPECT_EQ(r.holes_marked(), 6);
  EXPECT_TRUE(r.reason.empty());
  for (const auto& area : r.areas) {
    EXPECT_EQ(area.state, AreaState::kDone) << area.name;
    for (const auto& hole : area.holes) EXPECT_EQ(hole.state, HoleState::kDrilled);
  }
  ASSERT_TRUE(r.areas[1].located.base);
  EXPECT_DOUBLE_EQ(r.areas[1].located.base->theta, 0.5);
}

TEST(MissionTree, AFailedHoleIsRetractedAndTheNextOneDrilled) {
  FakePorts fake(2);
  fake.scripts["drill 0 blob 1 0.050"] = {2.0, "bit stalled"};
  fake.scripts["align 1 blob 2"] = {1.0, "out of reach"};
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);

  EXPECT_THAT(fake.calls_of("align 0 blob 2"), ElementsAre("align 0 blob 2"));
  EXPECT_EQ(fake.index_of("retract 0 blob 1"), fake.index_of("drill 0 blob 1 0.050") + 1);
  EXPECT_EQ(fake.index_of("align 0 blob 2"), fake.index_of("retract 0 blob 1") + 1);
  EXPECT_THAT(fake.calls_of("drill 1 blob 2"), IsEmpty()) << "not drilled where it is not aligned";
  EXPECT_EQ(fake.index_of("retract 1 blob 2"), fake.index_of("align 1 blob 2") + 1);

  const MissionReport& r = tree.report();
  EXPECT_EQ(r.areas[0].holes[0].state, HoleState::kFailed);
  EXPECT_EQ(r.areas[0].holes[0].reason, "drill: bit stalled");
  EXPECT_EQ(r.areas[0].holes[1].state, HoleState::kDrilled);
  EXPECT_EQ(r.areas[0].state, AreaState::kFailed);
  EXPECT_EQ(r.areas[0].reason, "1 of 2 holes failed (hole 'blob 1': drill: bit stalled)");
  EXPECT_EQ(r.areas[1].holes[1].reason, "align: out of reach");
  EXPECT_EQ(r.holes_drilled(), 2);
  EXPECT_EQ(r.reason,
            "2 of 4 holes failed; area 'a0': 1 of 2 holes failed (hole 'blob 1': drill: bit "
            "stalled); area 'a1': 1 of 2 holes failed (hole 'blob 2': align: out of reach)");
  EXPECT_THAT(fake.violations, IsEmpty());
}

TEST(MissionTree, AnAreaWhoseDetectionFailsIsLeftAndTheNextDrilled) {
  FakePorts fake(3);
  fake.scripts["detect 1"] = {1.0, "no blob visible"};
  MissionTree tree(mission_of(3), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);

  EXPECT_THAT(fake.calls_of("align 1"), IsEmpty());
  EXPECT_THAT(fake.calls_of("plan 2"), ElementsAre("plan 2 after 1"))
      << "the arm is still at area 1's approach posture";
  EXPECT_THAT(fake.calls_of("drill 2"), ::testing::SizeIs(2));
  EXPECT_THAT(fake.violations, IsEmpty());
  EXPECT_EQ(tree.report().areas[1].state, AreaState::kFailed);
  EXPECT_EQ(tree.report().areas[2].state, AreaState::kDone);
  EXPECT_EQ(tree.report().reason, "area 'a1': detect: no blob visible");
}

TEST(MissionTree, AnAreaThatCannotBeLocatedIsLeftOut) {
  FakePorts fake(3);
  fake.scripts["resolve 1"] = {0.0, "no wall with GlobalId 'x' in the model"};
  MissionTree tree(mission_of(3), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_THAT(fake.calls_of("resolve"), ElementsAre("resolve 0", "resolve 1", "resolve 2"));
  EXPECT_THAT(fake.calls_of("plan"), ElementsAre("plan 0 after none", "plan 2 after 0"));
  EXPECT_THAT(fake.calls_of("execute"), ElementsAre("execute 0", "execute 2"));
  EXPECT_EQ(tree.report().reason, "area 'a1': resolve: no wall with GlobalId 'x' in the model");
  EXPECT_THAT(fake.violations, IsEmpty());
}

TEST(MissionTree, AFailedApproachStopsTheRobotAndTheNextAreaIsPlannedFromWhereItIs) {
  FakePorts fake(2);
  fake.scripts["execute 0"] = {3.0, "joint 2 tracking error"};
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_EQ(fake.index_of("stop"), fake.index_of("execute 0") + 1);
  EXPECT_THAT(fake.calls_of("detect"), ElementsAre("detect 1"));
  EXPECT_THAT(fake.calls_of("plan 1"), ElementsAre("plan 1 after none"));
  EXPECT_THAT(fake.violations, IsEmpty());
  EXPECT_EQ(tree.report().areas[0].reason, "execute: joint 2 tracking error");
  EXPECT_EQ(tree.report().areas[1].state, AreaState::kDone);
}

TEST(MissionTree, AFailedPlacementStopsTheRobotAndFailsItsAreaOnly) {
  FakePorts fake(2);
  fake.scripts["place 0 2"] = {5.0, "robot: the base's placement: aborted"};
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_EQ(fake.index_of("stop"), fake.index_of("place 0 2") + 1);
  EXPECT_THAT(fake.calls_of("align 0"), IsEmpty()) << "no hole drilled from an unknown posture";
  EXPECT_THAT(fake.calls_of("drill"), ElementsAre("drill 1 blob 1 0.050", "drill 1 blob 2 0.050"));
  EXPECT_THAT(fake.violations, IsEmpty());
  EXPECT_EQ(tree.report().areas[0].state, AreaState::kFailed);
  EXPECT_EQ(tree.report().areas[0].reason, "place: robot: the base's placement: aborted");
  EXPECT_EQ(tree.report().areas[0].holes[0].state, HoleState::kPending);
  EXPECT_EQ(tree.report().areas[1].state, AreaState::kDone);
}

TEST(MissionTree, HolesAreDrilledInThePlacementsOrder) {
  FakePorts fake(1);
  const ResolvedArea& a = fake.areas[0];
  fake.points[0] = {FakePorts::blob(a, 1, 0.1), FakePorts::blob(a, 2, 0.0), FakePorts::blob(a, 3, -0.1)};
  fake.placement_order = {2, 0, 1};
  {
    MissionTree tree(mission_of(1), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
    EXPECT_THAT(fake.calls_of("drill"),
                ElementsAre("drill 0 blob 3 0.050", "drill 0 blob 1 0.050", "drill 0 blob 2 0.050"));
    ASSERT_EQ(tree.report().areas[0].holes.size(), 3u);
    EXPECT_EQ(tree.report().areas[0].holes[0].point.label, "blob 1") << "the report keeps the marks' order";
  }
  // An order that does not name every hole once is not taken.
  for (const std::vector<std::size_t>& bad :
       {std::vector<std::size_t>{2, 0}, std::vector<std::size_t>{0, 0, 1}, std::vector<std::size_t>{0, 1, 3}}) {
    fake.calls.clear();
    fake.placement_order = bad;
    MissionTree tree(mission_of(1), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
    EXPECT_THAT(fake.calls_of("drill"),
                ElementsAre("drill 0 blob 1 0.050", "drill 0 blob 2 0.050", "drill 0 blob 3 0.050"));
  }
}

TEST(MissionTree, APlacementsOrderCountsOnlyTheHolesStillToDrill) {
  // Resumed: blob 1 drilled before, the placement gets blobs 2 and 3 and orders them 3, 2.
  FakePorts fake(1);
  const ResolvedArea& a = fake.areas[0];
  fake.points[0] = {FakePorts::blob(a, 1, 0.1), FakePorts::blob(a, 2, 0.0), FakePorts::blob(a, 3, -0.1)};
  MissionReport first;
  {
    FakePorts once(1);
    once.points = fake.points;
    once.scripts["drill 0 blob 2 0.050"] = {1.0, "bit stalled"};
    once.scripts["drill 0 blob 3 0.050"] = {1.0, "bit stalled"};
    MissionTree tree(mission_of(1), once);
    run(tree, once);
    first = tree.report();
  }
  fake.placement_order = {1, 0};
  MissionTree tree(mission_of(1), fake);
  tree.resume(first);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
  EXPECT_THAT(fake.calls_of("place"), ElementsAre("place 0 2"));
  EXPECT_THAT(fake.calls_of("drill"), ElementsAre("drill 0 blob 3 0.050", "drill 0 blob 2 0.050"));
}

// What the sensors showed at the first survey may stand in the way only then: a hole judged
// unreachable is asked once more after the area's other holes were drilled (the robot stands
// elsewhere), and drilled if reachable then.
TEST(MissionTree, AnUnreachableHoleIsAskedAgainAfterTheOthersWereDrilled) {
  FakePorts fake(1);
  fake.verdicts["0 blob 2"] = {Reach::kUnreachable, "no posture: obstacles kept the camera off the task"};
  fake.on_call = [&fake](const std::string& call) {
    if (call == "drill 0 blob 1 0.050") fake.verdicts.clear();
  };
  MissionTree tree(mission_of(1), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
  EXPECT_THAT(fake.calls_of("survey"), ElementsAre("survey 0 2", "survey 0 1"));
  EXPECT_THAT(fake.calls_of("place"), ElementsAre("place 0 1", "place 0 1"));
  EXPECT_THAT(fake.calls_of("drill"), ElementsAre("drill 0 blob 1 0.050", "drill 0 blob 2 0.050"));
  const MissionReport& r = tree.report();
  EXPECT_EQ(r.areas[0].state, AreaState::kDone);
  EXPECT_EQ(r.areas[0].holes[1].state, HoleState::kDrilled);
  EXPECT_EQ(r.areas[0].holes[1].reach.reach, Reach::kReachable);
  EXPECT_EQ(r.holes_drilled(), 2);
}

// A second survey that fails leaves the hole as the first judged it: not drilled blind.
TEST(MissionTree, ASecondSurveyThatFailsKeepsTheFirstVerdict) {
  FakePorts fake(1);
  fake.verdicts["0 blob 2"] = {Reach::kUnreachable, "no posture"};
  fake.scripts["survey 0 1"] = {1.0, "the planner is gone"};
  MissionTree tree(mission_of(1), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_THAT(fake.calls_of("survey"), ElementsAre("survey 0 2", "survey 0 1"));
  EXPECT_THAT(fake.calls_of("drill"), ElementsAre("drill 0 blob 1 0.050"));
  const HoleReport& h = tree.report().areas[0].holes[1];
  EXPECT_EQ(h.state, HoleState::kSkipped);
  EXPECT_EQ(h.reach.reach, Reach::kUnreachable);
  EXPECT_EQ(h.reason, "unreachable: no posture");
}

// Asked again only once, and only when a hole of the area was drilled: with none drilled the
// robot has not moved.
TEST(MissionTree, NoHoleDrilledNoSecondSurvey) {
  FakePorts fake(1);
  fake.verdicts["0 blob 1"] = {Reach::kUnreachable, "no posture"};
  fake.verdicts["0 blob 2"] = {Reach::kUnreachable, "no posture"};
  MissionTree tree(mission_of(1), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_THAT(fake.calls_of("survey"), ElementsAre("survey 0 2"));
  EXPECT_THAT(fake.calls_of("place"), IsEmpty());
  EXPECT_THAT(fake.calls_of("drill"), IsEmpty());
  EXPECT_EQ(tree.report().areas[0].reason, "2 of 2 holes unreachable (hole 'blob 1': no posture)");
}

TEST(MissionTree, HolesTheSurveyFindsUnreachableAreReportedNotAttempted) {
  FakePorts fake(2);
  fake.verdicts["0 blob 2"] = {Reach::kUnreachable, "no posture: J3_E 163.9 N m over 160 continuous"};
  fake.verdicts["1 blob 1"] = {Reach::kUnknown, "the planner refused: another model"};
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  // Area 0's unreachable hole is asked once more after its other hole was drilled; still
  // unreachable, nothing is placed for it.
  EXPECT_THAT(fake.calls_of("survey"), ElementsAre("survey 0 2", "survey 0 1", "survey 1 2"));
  EXPECT_THAT(fake.calls_of("place"), ElementsAre("place 0 1", "place 1 2")) << "placed for the reachable only";
  EXPECT_THAT(fake.calls_of("drill"),
              ElementsAre("drill 0 blob 1 0.050", "drill 1 blob 1 0.050", "drill 1 blob 2 0.050"));
  const MissionReport& r = tree.report();
  const HoleReport& skipped = r.areas[0].holes[1];
  EXPECT_EQ(skipped.state, HoleState::kSkipped);
  EXPECT_EQ(skipped.reason, "unreachable: no posture: J3_E 163.9 N m over 160 continuous");
  EXPECT_EQ(skipped.reach.reach, Reach::kUnreachable);
  EXPECT_EQ(r.areas[0].holes[0].reach.reach, Reach::kReachable);
  EXPECT_EQ(r.areas[0].holes[0].reach.why, "at full thrust");
  EXPECT_EQ(r.areas[0].state, AreaState::kFailed);
  EXPECT_EQ(r.areas[0].reason,
            "1 of 2 holes unreachable (hole 'blob 2': no posture: J3_E 163.9 N m over 160 continuous)");
  // A hole the planner could not judge is drilled as if never asked.
  EXPECT_EQ(r.areas[1].holes[0].reach.reach, Reach::kUnknown);
  EXPECT_EQ(r.areas[1].holes[0].state, HoleState::kDrilled);
  EXPECT_EQ(r.areas[1].state, AreaState::kDone);
  EXPECT_EQ(r.holes_drilled(), 3);
  EXPECT_EQ(r.holes_marked(), 4);
}

TEST(MissionTree, AFailedSurveyLeavesTheHolesToBeAttempted) {
  FakePorts fake(1);
  fake.scripts["survey 0 2"] = {1.0, "no joint state"};
  MissionTree tree(mission_of(1), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
  EXPECT_EQ(tree.report().holes_drilled(), 2);
  EXPECT_EQ(tree.report().areas[0].holes[0].reach.reach, Reach::kUnknown);
}

TEST(MissionTree, AFailedPlanFailsItsAreaOnly) {
  FakePorts fake(2);
  fake.scripts["plan 0 after none"] = {2.0, "no approach without collision"};
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_THAT(fake.calls_of("execute"), ElementsAre("execute 1"));
  EXPECT_THAT(fake.calls_of("plan 1"), ElementsAre("plan 1 after none"));
  EXPECT_EQ(tree.report().reason, "area 'a0': plan: no approach without collision");
}

TEST(MissionTree, MoreHolesThanExpectedDrillsTheNearestToTheCentre) {
  FakePorts fake(1);
  const ResolvedArea& a = fake.areas[0];
  fake.points[0] = {FakePorts::blob(a, 1, 0.30), FakePorts::blob(a, 2, 0.02),
                    FakePorts::blob(a, 3, -0.04)};
  Mission m = mission_of(1);
  m.areas[0].expected = 2;
  MissionTree tree(m, fake);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
  EXPECT_THAT(fake.calls_of("drill"), ElementsAre("drill 0 blob 2 0.050", "drill 0 blob 3 0.050"));
  EXPECT_THAT(fake.calls_of("place"), ElementsAre("place 0 2")) << "placed for the holes to drill";
  const auto& holes = tree.report().areas[0].holes;
  ASSERT_EQ(holes.size(), 3u);
  EXPECT_EQ(holes[0].state, HoleState::kSkipped);
  EXPECT_EQ(holes[0].reason,
            "the area expects 2 holes and 3 were found: nearer ones to its centre are drilled");
  EXPECT_EQ(tree.report().holes_marked(), 3);
  EXPECT_EQ(tree.report().holes_drilled(), 2);
}

TEST(MissionTree, FewerHolesThanExpectedFailsTheAreaAfterDrillingThem) {
  FakePorts fake(1);
  Mission m = mission_of(1);
  m.areas[0].expected = 3;
  MissionTree tree(m, fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_EQ(tree.report().holes_drilled(), 2);
  EXPECT_EQ(tree.report().areas[0].reason, "1 of 3 expected holes not found");
  EXPECT_EQ(tree.report().reason, "area 'a0': 1 of 3 expected holes not found");
}

TEST(MissionTree, AnAreaWithoutPointsFails) {
  FakePorts fake(1);
  fake.points[0].clear();
  MissionTree tree(mission_of(1), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_EQ(tree.report().reason, "area 'a0': detect: no drilling point found");
}

TEST(MissionTree, HealthFailureMidDrillStopsEverything) {
  FakePorts fake(2);
  fake.scripts["drill 0 blob 2 0.050"] = {5.0, ""};
  fake.on_call = [&](const std::string& call) {
    if (call == "drill 0 blob 2 0.050") fake.unhealthy = "e-stop pressed";
  };
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kAborted);
  EXPECT_EQ(fake.calls.back(), "stop");
  EXPECT_EQ(fake.index_of("stop"), fake.index_of("drill 0 blob 2 0.050") + 1);

  const std::size_t calls = fake.calls.size();
  const int checks = fake.health_checks;
  fake.unhealthy.clear();
  fake.now += 1.0;
  EXPECT_EQ(tree.tick(fake.now), MissionState::kAborted) << "an aborted mission stays aborted";
  EXPECT_EQ(fake.calls.size(), calls);
  EXPECT_EQ(fake.health_checks, checks);

  const MissionReport& r = tree.report();
  EXPECT_EQ(r.reason, "health: e-stop pressed");
  EXPECT_EQ(r.areas[0].holes[0].state, HoleState::kDrilled);
  EXPECT_EQ(r.areas[0].holes[1].state, HoleState::kFailed);
  EXPECT_EQ(r.areas[0].holes[1].reason, "stopped: health: e-stop pressed");
  EXPECT_EQ(r.areas[0].state, AreaState::kFailed);
  EXPECT_EQ(r.areas[1].state, AreaState::kPending);
  EXPECT_EQ(tree.status().state, MissionState::kAborted);
  EXPECT_EQ(tree.status().active, "");
}

TEST(MissionTree, WaitsForServicesNotHeardYetThenRuns) {
  // A mission sent right after the stack started: the planner's status not heard yet. The
  // tree waits (nothing started, nothing failed) and then runs as usual.
  FakePorts fake(1);
  fake.unheard_checks = 3;
  MissionTree tree(mission_of(1), fake);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(tree.tick(fake.now), MissionState::kRunning) << i;
    fake.now += 0.1;
  }
  EXPECT_THAT(fake.calls, IsEmpty());
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
  EXPECT_EQ(tree.report().holes_drilled(), 2);
}

TEST(MissionTree, AbortStopsEverything) {
  FakePorts fake(2);
  fake.default_seconds = 1.0;
  MissionTree tree(mission_of(2), fake);
  while (fake.calls_of("drill").empty() && fake.now < 100.0) {
    ASSERT_EQ(tree.tick(fake.now), MissionState::kRunning);
    fake.now += 1.0;
  }
  ASSERT_EQ(tree.status().active, "mission/area 'a0'/hole 'blob 1'/drill");
  tree.abort("operator: cable in the way");
  EXPECT_EQ(fake.calls.back(), "stop");
  const std::size_t calls = fake.calls.size();
  EXPECT_EQ(tree.tick(fake.now + 1.0), MissionState::kAborted);
  tree.abort("again");
  EXPECT_EQ(fake.calls.size(), calls) << "no call after the abort, not even a second stop";
  EXPECT_EQ(tree.report().reason, "operator: cable in the way");
  EXPECT_EQ(tree.report().areas[0].holes[0].reason, "stopped: operator: cable in the way");
}

TEST(MissionTree, AFinishedMissionIgnoresAbort) {
  FakePorts fake(1);
  MissionTree tree(mission_of(1), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded);
  tree.abort("late");
  EXPECT_EQ(tree.report().state, MissionState::kSucceeded);
  EXPECT_THAT(fake.calls_of("stop"), IsEmpty());
}

TEST(MissionTree, AFailedRetractionStopsTheMission) {
  FakePorts fake(2);
  fake.scripts["retract 0 blob 1"] = {2.0, "bit stuck"};
  MissionTree tree(mission_of(2), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kFailed);
  EXPECT_EQ(fake.calls.back(), "stop");
  EXPECT_THAT(fake.calls_of("align"), ElementsAre("align 0 blob 1"));
  EXPECT_THAT(fake.calls_of("execute 1"), IsEmpty());
  EXPECT_EQ(tree.report().reason,
            "area 'a0' hole 'blob 1': retract: bit stuck; the arm is not back at the approach "
            "posture (the bit may be in the wall): mission stopped");
  EXPECT_EQ(tree.report().areas[0].state, AreaState::kFailed);
  EXPECT_EQ(tree.report().areas[0].holes[0].state, HoleState::kFailed);
}

TEST(MissionTree, ResumeSkipsDrilledHolesAndDoneAreas) {
  MissionReport first;
  {
    FakePorts fake(3);
    fake.scripts["drill 1 blob 2 0.050"] = {1.0, "bit stalled"};
    MissionTree tree(mission_of(3), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kFailed);
    first = tree.report();
  }
  MissionReport second;
  {
    FakePorts fake(3);
    // blob 1 is seen 5 mm from where it was drilled: the same hole
    fake.points[1][0].frame.translation() += Eigen::Vector3d(0.005, 0.0, 0.0);
    MissionTree tree(mission_of(3), fake);
    tree.resume(first);
    ASSERT_EQ(run(tree, fake), MissionState::kSucceeded) << tree.report().reason;
    EXPECT_THAT(fake.calls,
                ElementsAre("resolve 1", "plan 1 after none", "execute 1", "detect 1", "survey 1 1", "place 1 1",
                            "align 1 blob 2", "drill 1 blob 2 0.050", "retract 1 blob 2", "stow"));
    second = tree.report();
    EXPECT_EQ(second.areas[0].state, AreaState::kSkipped);
    EXPECT_EQ(second.areas[0].reason, kDoneBefore);
    EXPECT_EQ(second.areas[1].holes[0].state, HoleState::kSkipped);
    EXPECT_EQ(second.areas[1].holes[0].reason, kDrilledBefore);
    EXPECT_EQ(second.areas[1].holes[1].state, HoleState::kDrilled);
    EXPECT_EQ(second.holes_drilled(), 1);
    EXPECT_EQ(second.holes_marked(), 6);
  }
  {
    FakePorts fake(3);
    MissionTree tree(mission_of(3), fake);
    tree.resume(second);
    ASSERT_EQ(run(tree, fake), MissionState::kSucceeded);
    EXPECT_THAT(fake.calls, IsEmpty()) << "every area was done in one run or the other: nothing moved, nothing stowed";
  }
}

TEST(MissionTree, ResumeDrillsAHoleThatMovedMoreThanACentimetre) {
  MissionReport first;
  {
    FakePorts fake(1);
    fake.scripts["drill 0 blob 2 0.050"] = {1.0, "bit stalled"};
    MissionTree tree(mission_of(1), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kFailed);
    first = tree.report();
  }
  FakePorts fake(1);
  fake.points[0][0].frame.translation() += Eigen::Vector3d(0.0, 0.012, 0.0);
  MissionTree tree(mission_of(1), fake);
  tree.resume(first);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded);
  EXPECT_THAT(fake.calls_of("drill"), ElementsAre("drill 0 blob 1 0.050", "drill 0 blob 2 0.050"));
}

TEST(MissionTree, ResumeRefusesAnotherMissionOrAStartedOne) {
  FakePorts fake(1);
  MissionTree tree(mission_of(1), fake);
  MissionReport other;
  other.mission = "elsewhere";
  EXPECT_EQ(error_text<DrillError>([&] { tree.resume(other); }),
            "resume(): the report is of mission 'elsewhere', not 'test'");
  tree.tick(0.0);
  EXPECT_EQ(error_text<DrillError>([&] { tree.resume(tree.report()); }),
            "resume(): mission 'test' has started already");
}

// The arm goes home after the last area, whatever the areas' outcome; a homing that fails fails
// the mission with its reason and what to do, the holes drilled as they were. A fatal retraction
// (the bit may be in the wall) and an abort end the mission without it.
TEST(MissionTree, TheArmGoesHomeAtTheEndUnlessTheMissionHadToStop) {
  {
    FakePorts fake(2);
    fake.scripts["detect 1"] = {1.0, "no drilling point found"};
    MissionTree tree(mission_of(2), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kFailed);
    EXPECT_EQ(fake.calls.back(), "stow") << "after a failed area too";
    EXPECT_THAT(tree.report().reason, Not(HasSubstr("home")));
  }
  {
    FakePorts fake(1);
    fake.scripts["stow"] = {1.0, "home: the homing posture is rejected where the robot stands by environment collision"};
    MissionTree tree(mission_of(1), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kFailed);
    EXPECT_EQ(tree.report().holes_drilled(), 2);
    EXPECT_EQ(tree.report().areas[0].state, AreaState::kDone);
    EXPECT_THAT(tree.report().reason,
                HasSubstr("the arm did not go home at the end (home: the homing posture is rejected where the "
                          "robot stands by environment collision): move it clear, then `concert plan home`"));
  }
  {
    FakePorts fake(2);
    fake.scripts["retract 0 blob 1"] = {1.0, "bit stuck"};
    MissionTree tree(mission_of(2), fake);
    ASSERT_EQ(run(tree, fake), MissionState::kFailed);
    EXPECT_THAT(fake.calls_of("stow"), IsEmpty()) << "the bit may be in the wall";
  }
  {
    FakePorts fake(1);
    fake.scripts["drill 0 blob 1 0.050"] = {5.0, ""};
    MissionTree tree(mission_of(1), fake);
    fake.on_call = [&](const std::string& call) {
      if (call == "drill 0 blob 1 0.050") fake.unhealthy = "e-stop pressed";
    };
    ASSERT_EQ(run(tree, fake), MissionState::kAborted);
    EXPECT_THAT(fake.calls_of("stow"), IsEmpty());
  }
}

TEST(MissionTree, TimesAddUp) {
  FakePorts fake(3);
  fake.areas[2].base = BasePose{2.0, -1.0, 0.0};
  fake.default_seconds = 1.0;  // resolve, detect, survey, place, align, retract
  fake.scripts = {{"plan 0 after none", {3.0, ""}},
                  {"plan 1 after 0", {20.0, ""}},  // 11 s of it while area 0 is surveyed and drilled
                  {"plan 2 after none", {2.0, ""}},
                  {"navigate 2", {6.0, ""}}};
  for (const char* call : {"execute 0", "execute 1", "execute 2"}) fake.scripts[call] = {4.0, ""};
  for (int area = 0; area < 3; ++area) {
    for (int blob = 1; blob <= 2; ++blob) {
      fake.scripts["drill " + std::to_string(area) + " blob " + std::to_string(blob) + " 0.050"] = {
          2.0, ""};
    }
  }
  MissionTree tree(mission_of(3), fake);
  ASSERT_EQ(run(tree, fake), MissionState::kSucceeded);
  EXPECT_THAT(fake.violations, IsEmpty());

  const MissionTimes& t = tree.report().times;
  EXPECT_DOUBLE_EQ(t.navigate, 6.0);
  EXPECT_DOUBLE_EQ(t.plan, 3.0 + 9.0 + 2.0 + 3 * 1.0);  // the approaches waited for, the surveys
  EXPECT_DOUBLE_EQ(t.execute, 3 * 4.0 + 1.0);  // the approaches, the arm home at the end
  EXPECT_DOUBLE_EQ(t.drill, 3 * (1.0 + 1.0 + 2 * (1.0 + 2.0 + 1.0)));  // detect, place, holes
  const double resolve = 3 * 1.0;
  EXPECT_DOUBLE_EQ(t.total, fake.now);
  EXPECT_DOUBLE_EQ(t.navigate + t.plan + t.execute + t.drill + resolve, t.total);
  EXPECT_EQ(fake.health_checks, static_cast<int>(fake.now) + 1) << "one check a tick";

  // Per area and hole: the approach is navigating, the plan waited for and its execution.
  const std::vector<double> approach{3.0 + 4.0, 9.0 + 4.0, 6.0 + 2.0 + 4.0};
  for (std::size_t i = 0; i < 3; ++i) {
    const AreaReport& a = tree.report().areas[i];
    EXPECT_DOUBLE_EQ(a.times.approach, approach[i]) << "area " << i;
    EXPECT_DOUBLE_EQ(a.times.detect, 1.0) << "area " << i;
    EXPECT_DOUBLE_EQ(a.times.survey, 1.0) << "area " << i;
    EXPECT_DOUBLE_EQ(a.times.place, 1.0) << "area " << i;
    for (const HoleReport& h : a.holes) {
      EXPECT_DOUBLE_EQ(h.times.align, 1.0) << "area " << i << " " << h.point.label;
      EXPECT_DOUBLE_EQ(h.times.drill, 2.0) << "area " << i << " " << h.point.label;
      EXPECT_DOUBLE_EQ(h.times.retract, 1.0) << "area " << i << " " << h.point.label;
    }
  }
}

TEST(MissionTree, StatusNamesTheActiveNode) {
  FakePorts fake(2);
  fake.areas[1].base = BasePose{1.0, -1.0, 0.0};
  fake.default_seconds = 1.0;
  MissionTree tree(mission_of(2), fake);
  EXPECT_EQ(tree.status().state, MissionState::kIdle);
  EXPECT_EQ(tree.status().active, "");

  std::vector<std::string> paths;
  bool checked_indices = false;
  for (MissionState s = MissionState::kRunning; s == MissionState::kRunning; fake.now += 1.0) {
    s = tree.tick(fake.now);
    const MissionStatus status = tree.status();
    if (paths.empty() || paths.back() != status.active) paths.push_back(status.active);
    if (status.active == "mission/area 'a1'/hole 'blob 2'/retract") {
      EXPECT_EQ(status.area, 1u);
      EXPECT_EQ(status.hole, 1u);
      checked_indices = true;
    }
    ASSERT_LT(fake.now, 1000.0);
  }
  EXPECT_TRUE(checked_indices);
  auto holes = [](const std::string& area) {
    std::vector<std::string> out;
    for (const char* blob : {"blob 1", "blob 2"}) {
      for (const char* step : {"align", "drill", "retract"}) {
        out.push_back("mission/area '" + area + "'/hole '" + blob + "'/" + step);
      }
    }
    out.insert(out.begin(), {"mission/area '" + area + "'/survey", "mission/area '" + area + "'/place"});
    return out;
  };
  EXPECT_THAT(
      paths,
      ElementsAreArray(concat({
          {"mission/initialise/area 'a0'/resolve", "mission/initialise/area 'a1'/resolve",
           "mission/area 'a0'/plan", "mission/area 'a0'/execute", "mission/area 'a0'/detect"},
          holes("a0"),
          {"mission/area 'a1'/navigate", "mission/area 'a1'/plan", "mission/area 'a1'/execute",
           "mission/area 'a1'/detect"},
          holes("a1"),
          {"mission/stow the arm", ""},
      })));
}

TEST(MissionTree, DescribesItsShape) {
  FakePorts fake(1);
  MissionTree tree(mission_of(1), fake);
  EXPECT_EQ(tree.describe(),
            "mission (sequence)\n"
            "  initialise (sequence)\n"
            "    areas (for each)\n"
            "      resolve (action)\n"
            "  areas (for each)\n"
            "    area (sequence)\n"
            "      navigate if the area has a base pose (fallback)\n"
            "        no base pose (condition)\n"
            "        navigate (action)\n"
            "      plan (action)\n"
            "      execute (action)\n"
            "      plan the next area (action)\n"
            "      detect (action)\n"
            "      survey and drill (sequence)\n"
            "        survey (action)\n"
            "        drill the reachable holes (fallback)\n"
            "          no hole reachable (condition)\n"
            "          place and drill (sequence)\n"
            "            place (action)\n"
            "            holes (for each)\n"
            "              hole (finally)\n"
            "                align and drill (sequence)\n"
            "                  align (action)\n"
            "                  drill (action)\n"
            "                retract (action)\n"
            "      survey again (fallback)\n"
            "        nothing to ask again (condition)\n"
            "        survey and drill again (sequence)\n"
            "          survey again (action)\n"
            "          drill the reachable holes (fallback)\n"
            "            no hole reachable (condition)\n"
            "            place and drill (sequence)\n"
            "              place (action)\n"
            "              holes (for each)\n"
            "                hole (finally)\n"
            "                  align and drill (sequence)\n"
            "                    align (action)\n"
            "                    drill (action)\n"
            "                  retract (action)\n"
            "  stow the arm if anything moved (fallback)\n"
            "    nothing moved (condition)\n"
            "    stow the arm (action)\n");
}

TEST(MissionTree, StateNames) {
  EXPECT_STREQ(to_string(HoleState::kSkipped), "skipped");
  EXPECT_STREQ(to_string(AreaState::kActive), "active");
  EXPECT_STREQ(to_string(MissionState::kAborted), "aborted");
}

}  // namespace
}  // namespace concert::drill
