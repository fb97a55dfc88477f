// Fig. 12: every (state, command) pair of the eight reachable states and eight commands, the
// paper's two shortcuts, the e-stop, and the text parser with its wake phrase.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "collab/command_parser.hpp"
#include "collab/state_machine.hpp"

namespace concert::collab {
namespace {

using C = Command;
using M = Mode;
using S = SubState;

// Drives a fresh machine into `target` with accepted commands only.
StateMachine reach(const State& target) {
  StateMachine sm;
  auto must = [&](C c) {
    const auto t = sm.apply(c);
    EXPECT_TRUE(t.accepted) << command_name(c) << ": " << t.reason;
  };
  switch (target.mode) {
    case M::kStop:
      break;
    case M::kFollowMe:
      must(C::kFollowMe);
      break;
    case M::kTeaching:
      must(C::kTeaching);
      if (target.sub == S::kOpen) must(C::kOpen);
      if (target.sub == S::kClose) must(C::kClose);
      break;
    case M::kAutonomous:
      must(C::kAutonomous);
      if (target.sub == S::kLift) must(C::kLift);
      if (target.sub == S::kPlace) must(C::kPlace);
      break;
  }
  EXPECT_EQ(sm.state(), target) << state_name(sm.state());
  return sm;
}

const std::vector<State> kStates{
    {M::kTeaching, S::kGeneral}, {M::kTeaching, S::kOpen},   {M::kTeaching, S::kClose},
    {M::kAutonomous, S::kHold},  {M::kAutonomous, S::kLift}, {M::kAutonomous, S::kPlace},
    {M::kFollowMe, S::kNone},    {M::kStop, S::kNone}};

// The expected result of each command in each state: the next state, or nullopt when ignored.
std::optional<State> expected(const State& s, C c) {
  const State teaching{M::kTeaching, S::kGeneral};
  const State hold{M::kAutonomous, S::kHold};
  const State lift{M::kAutonomous, S::kLift};
  const State place{M::kAutonomous, S::kPlace};
  const State follow{M::kFollowMe, S::kNone};
  const State stop{M::kStop, S::kNone};
  std::optional<State> next;
  switch (c) {
    case C::kTeaching:
      if (s.mode != M::kTeaching) next = teaching;
      break;
    case C::kAutonomous:
      if (s.mode != M::kAutonomous) next = hold;
      break;
    case C::kFollowMe:
      next = follow;
      break;
    case C::kStop:
      next = stop;
      break;
    case C::kOpen:
      if (s.mode == M::kTeaching) next = State{M::kTeaching, S::kOpen};
      break;
    case C::kClose:
      if (s.mode == M::kTeaching) next = State{M::kTeaching, S::kClose};
      break;
    case C::kLift:
      if (s.mode == M::kTeaching || s.mode == M::kAutonomous) next = lift;
      break;
    case C::kPlace:
      if (s.mode == M::kFollowMe || s.mode == M::kAutonomous) next = place;
      break;
  }
  if (next && *next == s) next.reset();  // "already": ignored
  return next;
}

TEST(StateMachine, StartsInStop) {
  StateMachine sm;
  EXPECT_EQ(sm.state(), (State{M::kStop, S::kNone}));
  EXPECT_EQ(state_name(sm.state()), "stop");
}

TEST(StateMachine, EveryCommandInEveryState) {
  int accepted = 0;
  int ignored = 0;
  for (const auto& s : kStates) {
    for (C c : kAllCommands) {
      StateMachine sm = reach(s);
      const auto t = sm.apply(c);
      const auto want = expected(s, c);
      SCOPED_TRACE(state_name(s) + " + " + command_name(c));
      EXPECT_EQ(t.from, s);
      EXPECT_EQ(t.command, c);
      if (want) {
        ++accepted;
        EXPECT_TRUE(t.accepted) << t.reason;
        EXPECT_TRUE(t.reason.empty());
        EXPECT_EQ(t.to, *want) << state_name(t.to);
        EXPECT_EQ(sm.state(), *want);
      } else {
        ++ignored;
        EXPECT_FALSE(t.accepted);
        EXPECT_FALSE(t.reason.empty());
        EXPECT_EQ(t.to, s);
        EXPECT_EQ(sm.state(), s) << "an ignored command changed the state";
      }
    }
  }
  // 8 states x 8 commands; the count pins the table's shape (a change to it shows here).
  EXPECT_EQ(accepted + ignored, 64);
  EXPECT_EQ(accepted, 36);
  EXPECT_EQ(ignored, 28);
}

TEST(StateMachine, PaperShortcuts) {
  // "lift" in teaching switches to autonomous and lifts; "place" in follow-me switches to
  // autonomous and places (paper section 5.5).
  StateMachine sm = reach({M::kTeaching, S::kClose});
  auto t = sm.apply(C::kLift);
  ASSERT_TRUE(t.accepted);
  EXPECT_EQ(state_name(sm.state()), "autonomous/lift");
  sm.apply(C::kFollowMe);
  t = sm.apply(C::kPlace);
  ASSERT_TRUE(t.accepted);
  EXPECT_EQ(state_name(sm.state()), "autonomous/place");
}

TEST(StateMachine, OpenIgnoredOutsideTeachingToAvoidDrops) {
  for (const State& s : {State{M::kAutonomous, S::kLift}, State{M::kFollowMe, S::kNone}}) {
    StateMachine sm = reach(s);
    const auto t = sm.apply(C::kOpen);
    EXPECT_FALSE(t.accepted);
    EXPECT_NE(t.reason.find("load"), std::string::npos) << t.reason;
    EXPECT_EQ(sm.state(), s);
  }
}

TEST(StateMachine, PaperExperimentSequence) {
  // Fig. 13: teaching -> close -> lift -> follow me -> place -> teaching -> open -> follow me
  // -> teaching -> close -> autonomous.
  StateMachine sm;
  const std::vector<std::pair<C, std::string>> steps{
      {C::kTeaching, "teaching/general"}, {C::kClose, "teaching/close"},   {C::kLift, "autonomous/lift"},
      {C::kFollowMe, "follow-me"},        {C::kPlace, "autonomous/place"}, {C::kTeaching, "teaching/general"},
      {C::kOpen, "teaching/open"},        {C::kFollowMe, "follow-me"},     {C::kTeaching, "teaching/general"},
      {C::kClose, "teaching/close"},      {C::kAutonomous, "autonomous/hold"}};
  for (const auto& [c, name] : steps) {
    const auto t = sm.apply(c);
    EXPECT_TRUE(t.accepted) << command_name(c) << ": " << t.reason;
    EXPECT_EQ(state_name(sm.state()), name);
  }
}

TEST(StateMachine, EstopForcesStopFromEveryStateAndLatches) {
  for (const auto& s : kStates) {
    StateMachine sm = reach(s);
    const auto t = sm.set_estop(true);
    EXPECT_EQ(t.accepted, s.mode != M::kStop);
    EXPECT_EQ(sm.state(), (State{M::kStop, S::kNone}));
    EXPECT_TRUE(sm.estop_active());
    for (C c : kAllCommands) {
      const auto r = sm.apply(c);
      EXPECT_FALSE(r.accepted) << command_name(c);
      EXPECT_NE(r.reason.find("e-stop"), std::string::npos) << r.reason;
      EXPECT_EQ(sm.state().mode, M::kStop);
    }
    sm.set_estop(false);
    EXPECT_FALSE(sm.estop_active());
    EXPECT_EQ(sm.state().mode, M::kStop) << "releasing the e-stop must not leave stop";
    EXPECT_TRUE(sm.apply(C::kTeaching).accepted);
  }
}

TEST(StateMachine, ParseMode) {
  EXPECT_EQ(parse_mode("teaching"), M::kTeaching);
  EXPECT_EQ(parse_mode("Follow-Me"), M::kFollowMe);
  EXPECT_EQ(parse_mode("follow_me"), M::kFollowMe);
  EXPECT_EQ(parse_mode("autonomous"), M::kAutonomous);
  EXPECT_EQ(parse_mode("stop"), M::kStop);
  EXPECT_FALSE(parse_mode("lift"));
  EXPECT_FALSE(parse_mode(""));
}

TEST(CommandParser, EveryCommandWithWakePhrase) {
  for (C c : kAllCommands) {
    const auto p = parse_command(std::string("Hey CONCERT, ") + command_phrase(c) + ".");
    ASSERT_TRUE(p.command) << command_phrase(c) << ": " << p.reason;
    EXPECT_EQ(*p.command, c);
  }
  EXPECT_EQ(parse_command("hey concert follow me").command, C::kFollowMe);
  EXPECT_EQ(parse_command("  HEY   concert!!  stop ").command, C::kStop);
  // Speech before the wake phrase does not matter; the last wake phrase counts.
  EXPECT_EQ(parse_command("ok then hey concert lift").command, C::kLift);
  EXPECT_EQ(parse_command("hey concert hey concert place").command, C::kPlace);
}

TEST(CommandParser, RejectsWithReason) {
  const std::vector<std::pair<std::string, std::string>> bad{
      {"follow me", "wake phrase"},
      {"stop", "wake phrase"},
      {"", "empty"},
      {"hey concert", "without a command"},
      {"hey concert, dance", "unknown command"},
      {"hey concert follow me please", "unknown command"},
      {"hey concert follow", "unknown command"},
      {"hey, lift the box", "wake phrase"},
      {"concert hey lift", "wake phrase"},
  };
  for (const auto& [text, why] : bad) {
    const auto p = parse_command(text);
    EXPECT_FALSE(p.command) << text;
    EXPECT_NE(p.reason.find(why), std::string::npos) << text << " -> " << p.reason;
  }
}

TEST(CommandParser, NormaliseWords) {
  EXPECT_EQ(normalise_words("Hey, CONCERT... follow-me!"),
            (std::vector<std::string>{"hey", "concert", "follow", "me"}));
  EXPECT_TRUE(normalise_words(" ,.; ").empty());
}

}  // namespace
}  // namespace concert::collab
