// The service's decisions on a request, without DDS (planner/request.hpp): which start state a
// request gets, when it is refused and why, and the frame its goals are planned in and its
// trajectories come back through. Morphology A of the paper, built from its assembly file.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "planner/fixtures.hpp"
#include "planner/request.hpp"

using namespace concert::planner;

namespace {

std::shared_ptr<const PlanningModel> morphology_a() {
  static const auto model =
      PlanningModel::build(fixtures::model_from_assembly(fixtures::data_dir() / "morphology_a.yaml", 7), Params{});
  return model;
}

ClientRequest request_for(const PlanningModel& model) {
  ClientRequest r;
  r.plan.request_id = 42;
  r.plan.model_version = model.version();
  r.plan.goals.push_back({fixtures::drilling_area(1.5, 0.0, 1.2)});
  return r;
}

// The robot standing at odometry (x, y, yaw) with every arm joint at 0.1 rad.
MeasuredRobot robot_at(const PlanningModel& model, const Eigen::Vector3d& odometry) {
  MeasuredRobot robot;
  robot.odometry = odometry;
  MeasuredRobot::Joints joints;
  joints.model_version = model.version();
  for (const std::string& name : model.joint_names()) {
    if (name.rfind("base_", 0) == 0) continue;
    joints.names.push_back(name);
    joints.positions.push_back(0.1);
  }
  robot.joints = joints;
  return robot;
}

}  // namespace

TEST(PrepareRequest, StartsFromTheMeasuredRobotAtItsOdometry) {
  const auto model = morphology_a();
  const PreparedRequest p =
      prepare_request(request_for(*model), model.get(), robot_at(*model, {0.4, -0.2, 0.3}), FrameKnowledge{});
  ASSERT_FALSE(p.refused()) << p.reason;
  ASSERT_EQ(p.start.size(), model->full_dof());
  EXPECT_NEAR(p.start(0), 0.4, 1e-12);
  EXPECT_NEAR(p.start(1), -0.2, 1e-12);
  EXPECT_NEAR(p.start(2), 0.3, 1e-12);
  EXPECT_NEAR(p.yaw_offset, 0.0, 1e-12);
  EXPECT_TRUE(p.frame_note.empty());
}

TEST(PrepareRequest, ExecutingNeedsAJointStateOfThisModel) {
  const auto model = morphology_a();
  ClientRequest r = request_for(*model);
  r.execute = true;
  PreparedRequest p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  EXPECT_EQ(p.refusal, Status::kInvalidStart);
  EXPECT_EQ(p.reason, "no joint state from the robot service yet (needed to execute)");

  MeasuredRobot other = robot_at(*model, {0, 0, 0});
  other.joints->model_version = model->version() - 1;
  p = prepare_request(r, model.get(), other, FrameKnowledge{});
  EXPECT_EQ(p.refusal, Status::kInvalidStart);
  EXPECT_EQ(p.reason, "the robot runs model version 6, the planner 7");

  // Planning only: the model's zero posture where odometry puts the base.
  r.execute = false;
  p = prepare_request(r, model.get(), MeasuredRobot{{}, Eigen::Vector3d(1.0, 2.0, 0.5)}, FrameKnowledge{});
  ASSERT_FALSE(p.refused()) << p.reason;
  EXPECT_NEAR(p.start(0), 1.0, 1e-12);
  EXPECT_NEAR(p.start(2), 0.5, 1e-12);
  EXPECT_NEAR(p.start.tail(p.start.size() - 3).norm(), 0.0, 1e-12);
}

TEST(PrepareRequest, AGivenStartStateIsCheckedAndCannotBeExecuted) {
  const auto model = morphology_a();
  ClientRequest r = request_for(*model);
  r.start_names = {"base_x", "no_such_joint"};
  r.start_position = {0.5, 0.1};
  PreparedRequest p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  EXPECT_EQ(p.refusal, Status::kInvalidStart);
  EXPECT_NE(p.reason.find("no_such_joint"), std::string::npos) << p.reason;

  r.start_names = {"base_x", "base_yaw"};
  r.start_position = {0.5, std::nan("")};
  p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  EXPECT_EQ(p.reason, "start state: 'base_yaw' is not finite");

  r.start_position = {0.5};
  p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  EXPECT_EQ(p.reason, "start state has 2 names and 1 positions");

  r.start_position = {0.5, 0.25};
  p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  ASSERT_FALSE(p.refused()) << p.reason;
  EXPECT_NEAR(p.start(0), 0.5, 1e-12);
  EXPECT_NEAR(p.start(2), 0.25, 1e-12);

  r.execute = true;
  p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  EXPECT_EQ(p.refusal, Status::kInvalidStart);
  EXPECT_EQ(p.reason, "a request with a start state cannot be executed (the robot is not there)");
}

TEST(PrepareRequest, AStaleVersionIsLeftToThePlanner) {
  const auto model = morphology_a();
  ClientRequest r = request_for(*model);
  r.plan.model_version = model->version() + 1;
  r.execute = true;
  const PreparedRequest p = prepare_request(r, model.get(), MeasuredRobot{}, FrameKnowledge{});
  EXPECT_FALSE(p.refused());
  EXPECT_EQ(p.start.size(), 0);
  const PreparedRequest none = prepare_request(r, nullptr, MeasuredRobot{}, FrameKnowledge{});
  EXPECT_FALSE(none.refused());
  EXPECT_EQ(none.start.size(), 0);
}

TEST(PrepareRequest, TheClientsOdometryFramePlacesGoalsAndStartInTheMap) {
  const auto model = morphology_a();
  ClientRequest r = request_for(*model);
  r.odom_in_map = {1.0, -0.5, 0.5};
  // Odometry yaw near +pi: in the map it wraps to about -2.78 rad.
  const PreparedRequest p = prepare_request(r, model.get(), robot_at(*model, {0.2, 0.1, 3.0}), FrameKnowledge{});
  ASSERT_FALSE(p.refused()) << p.reason;
  EXPECT_NE(p.frame_note.find("as the client measured it"), std::string::npos) << p.frame_note;
  const Eigen::Isometry3d map_from_odom =
      Eigen::Translation3d(1.0, -0.5, 0.0) * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d expected_goal = map_from_odom * r.plan.goals[0].area;
  EXPECT_TRUE(p.plan.goals[0].area.isApprox(expected_goal, 1e-12));
  const Eigen::Vector3d start_map = map_from_odom * Eigen::Vector3d(0.2, 0.1, 0.0);
  EXPECT_NEAR(p.start(0), start_map.x(), 1e-12);
  EXPECT_NEAR(p.start(1), start_map.y(), 1e-12);
  EXPECT_LT(p.start(2), -2.7);  // wrapped

  // A trajectory that starts at the start goes back into odometry continuous: yaw 3.0, not -3.28.
  Trajectory t;
  t.joint_names = {"base_x", "base_y", "base_yaw"};
  t.points.push_back({0.0, p.start.head<3>(), Eigen::Vector3d(0.1, 0.0, 0.0)});
  const Trajectory back = to_odometry_frame(t, p.map_T_odom, p.yaw_offset);
  EXPECT_NEAR(back.points[0].q(0), 0.2, 1e-12);
  EXPECT_NEAR(back.points[0].q(1), 0.1, 1e-12);
  EXPECT_NEAR(back.points[0].q(2), 3.0, 1e-12);
  // The velocity turned back by the frame's yaw.
  EXPECT_NEAR(back.points[0].qd(0), 0.1 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(back.points[0].qd(1), -0.1 * std::sin(0.5), 1e-12);
}

TEST(PrepareRequest, AMalformedOdometryFrameIsRefusedAndSensorsKeepNavsFrame) {
  const auto model = morphology_a();
  ClientRequest r = request_for(*model);
  r.odom_in_map = {1.0, 2.0};
  PreparedRequest p = prepare_request(r, model.get(), robot_at(*model, {0, 0, 0}), FrameKnowledge{});
  EXPECT_EQ(p.refusal, Status::kInvalidRequest);
  EXPECT_EQ(p.reason, "odom_in_map needs 3 finite values (x, y, yaw), got 2");
  r.odom_in_map = {1.0, 2.0, std::nan("")};
  p = prepare_request(r, model.get(), robot_at(*model, {0, 0, 0}), FrameKnowledge{});
  EXPECT_EQ(p.refusal, Status::kInvalidRequest);

  // The map from the sensors is placed with nav's frame: the client's is not used.
  r.odom_in_map = {1.0, 2.0, 0.0};
  FrameKnowledge nav;
  nav.map_T_odom = Eigen::Vector3d(-1.0, 0.0, 0.0);
  nav.localised = true;
  nav.map_from_sensors = true;
  p = prepare_request(r, model.get(), robot_at(*model, {0, 0, 0}), nav);
  ASSERT_FALSE(p.refused()) << p.reason;
  EXPECT_NEAR(p.start(0), -1.0, 1e-12);
  EXPECT_NE(p.frame_note.find("not used: the map comes from the sensors"), std::string::npos) << p.frame_note;
}

TEST(PrepareRequest, TheLogLineNamesStatusFrameAndEachPlannedGoal) {
  const auto model = morphology_a();
  FrameKnowledge nav;
  nav.map_T_odom = Eigen::Vector3d(0.5, 0.0, 0.0);
  nav.localised = true;
  const PreparedRequest p = prepare_request(request_for(*model), model.get(), robot_at(*model, {0, 0, 0}), nav);
  PlanResult result;
  result.request_id = 42;
  result.status = Status::kSucceeded;
  GoalResult g;
  g.index = 0;
  g.status = Status::kSucceeded;
  g.nspg_seconds = 0.25;
  g.plan_seconds = 0.5;
  g.path_method = "direct";
  g.load = "J2_E 0.91";
  result.goals.push_back(g);
  const std::string line = describe(result, p, nav);
  EXPECT_NE(line.find("planner: request 42: "), std::string::npos) << line;
  EXPECT_NE(line.find("planned in the map, odometry frame at (0.5, 0, 0)"), std::string::npos) << line;
  EXPECT_NE(line.find("goal 0 in 750 ms (direct; load J2_E 0.91)"), std::string::npos) << line;
}
