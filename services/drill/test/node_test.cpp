// The drill service's DDS adapter: a mission message written again (same id and stamp, as
// `concert drill run` does until a status names it) is taken once; a new stamp is a new request.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <chrono>
#include <sstream>
#include <string>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "dds/drill_node.hpp"

namespace concert::drill::dds {
namespace {

using namespace std::chrono_literals;

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(DrillNode, AMissionWrittenAgainIsTakenOnce) {
  concert::dds::Participant participant({.name = "drill_node_test"});
  std::ostringstream log;
  DrillNode node(participant, NodeParams{}, log);
  std::atomic<bool> stop{false};
  std::thread spinner([&] { node.spin(stop); });
  concert::dds::Writer<msg::DrillMission> missions(participant, concert::dds::topics::drill_mission);
  ASSERT_TRUE(missions.wait_for_readers(1, 5s));

  // No robot model: the service refuses the mission, once for the three copies.
  msg::DrillMission m;
  m.mission_id(7);
  m.stamp_ns(now_ns());
  m.source("test");
  m.name("twice");
  m.yaml("areas:\n  - {point: [2.2, 0.0, 1.2]}\n");
  for (int i = 0; i < 3; ++i) {
    missions.write(m);
    std::this_thread::sleep_for(200ms);
  }
  // The same mission id sent anew (a new stamp) is a new request: refused again.
  m.stamp_ns(m.stamp_ns() + 1);
  missions.write(m);
  // Then another mission: the service takes missions in order, so once it refused that one it
  // had handled every copy of mission 7 (bounded wait).
  msg::DrillMission next = m;
  next.mission_id(8);
  missions.write(next);
  for (int i = 0; i < 300 && count(log.str(), "mission 8 refused") < 1; ++i)
    std::this_thread::sleep_for(100ms);
  stop = true;
  spinner.join();
  EXPECT_EQ(count(log.str(), "mission 8 refused: no robot model yet"), 1u) << log.str();
  EXPECT_EQ(count(log.str(), "mission 7 refused: no robot model yet"), 2u) << log.str();
}

}  // namespace
}  // namespace concert::drill::dds

namespace concert::drill::dds {
namespace {

// The robot's and nav's words as the core reads them: running, done, or failed saying how.
TEST(DrillConversions, TrajectoryAndNavStatusesBecomeProgressWithHowTheyFailed) {
  msg::TrajectoryStatus t;
  t.state(msg::TRAJECTORY_EXECUTING);
  EXPECT_EQ(to_core(t).progress, Progress::kRunning);
  t.state(msg::TRAJECTORY_SUCCEEDED);
  EXPECT_EQ(to_core(t).progress, Progress::kSucceeded);
  t.state(msg::TRAJECTORY_REFUSED);
  t.reason("stale model version 3");
  EXPECT_EQ(to_core(t).progress, Progress::kFailed);
  EXPECT_EQ(to_core(t).failure, "refused");
  EXPECT_EQ(to_core(t).reason, "stale model version 3");
  t.state(msg::TRAJECTORY_ABORTED);
  EXPECT_EQ(to_core(t).failure, "aborted");

  msg::NavStatus n;
  for (const auto s : {msg::NAV_IDLE, msg::NAV_PLANNING, msg::NAV_FOLLOWING}) {
    n.state(s);
    EXPECT_EQ(to_core(n).progress, Progress::kRunning);
  }
  n.state(msg::NAV_REACHED);
  EXPECT_EQ(to_core(n).progress, Progress::kSucceeded);
  n.state(msg::NAV_CANCELLED);
  EXPECT_EQ(to_core(n).progress, Progress::kFailed);
  EXPECT_EQ(to_core(n).failure, "cancelled");

  msg::SafetyState st;
  st.mode(msg::SAFETY_STOPPED);
  st.causes({"estop: software engaged"});
  EXPECT_FALSE(to_core(st).running);
  EXPECT_EQ(to_core(st).causes.size(), 1u);
}

// The mission's status message: each state onto its wire twin, the holes counted.
TEST(DrillConversions, TheStatusCarriesTheMissionsAreasAndHolesStates) {
  MissionReport report;
  report.mission = "m";
  AreaReport area;
  area.name = "a";
  area.state = AreaState::kSkipped;
  HoleReport drilled;
  drilled.state = HoleState::kDrilled;
  HoleReport skipped;
  skipped.state = HoleState::kSkipped;
  area.holes = {drilled, skipped};
  report.areas = {area};
  MissionStatus status;
  status.state = MissionState::kAborted;
  const msg::DrillStatus out = to_msg(3, status, report);
  EXPECT_EQ(out.mission_id(), 3u);
  EXPECT_EQ(out.state(), msg::DRILL_ABORTED);
  ASSERT_EQ(out.areas().size(), 1u);
  EXPECT_EQ(out.areas()[0].state(), msg::AREA_SKIPPED);
  ASSERT_EQ(out.areas()[0].holes().size(), 2u);
  EXPECT_EQ(out.areas()[0].holes()[0].state(), msg::HOLE_DRILLED);
  EXPECT_EQ(out.areas()[0].holes()[1].state(), msg::HOLE_SKIPPED);
  EXPECT_EQ(out.holes_drilled(), 1u);
}

// A planner state this build does not know is a failure, never progress.
TEST(DrillConversions, APlanResultBecomesAReplyWithItsTrajectory) {
  msg::PlanResult r;
  r.request_id(9);
  r.state(msg::PLAN_FAILED);
  r.failure(msg::PLAN_NO_PATH);
  r.reason("no path");
  r.joint_names({"base_x"});
  msg::TrajectorySample s;
  s.time(0.5);
  s.position({1.0});
  r.trajectory().push_back(s);
  const PlanReply p = to_core(r);
  EXPECT_EQ(p.request_id, 9u);
  EXPECT_EQ(p.state, PlanState::kFailed);
  EXPECT_EQ(p.failure, PlanFailure::kNoPath);
  EXPECT_EQ(p.reason, "no path");
  ASSERT_EQ(p.path.samples.size(), 1u);
  EXPECT_DOUBLE_EQ(p.path.samples[0].time, 0.5);
  r.state(static_cast<msg::PlanState>(42));
  EXPECT_EQ(to_core(r).state, PlanState::kFailed);
}

}  // namespace
}  // namespace concert::drill::dds
