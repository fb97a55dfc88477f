// Controller switching at cycle boundaries and closed-loop joint trajectories.
#include <gtest/gtest.h>

#include <cmath>

#include "robot/robot_core.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

using test::hw_index;
using test::read_fixture;
using test::run_cycles;

/// Quintic (rest-to-rest) profile from `a` to `b` over `duration` [s], `count` samples.
JointTrajectory rest_to_rest(std::uint64_t version, const std::vector<std::string>& joints,
                             const std::vector<double>& a, const std::vector<double>& b, double duration,
                             int count) {
  JointTrajectory t;
  t.model_version = version;
  t.request_id = 11;
  t.source = "test";
  t.joints = joints;
  for (int k = 0; k <= count; ++k) {
    const double tau = static_cast<double>(k) / count;
    const double s = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
    const double ds = 30 * tau * tau * (1 - tau) * (1 - tau) / duration;
    TrajectorySample p;
    p.time = duration * tau;
    for (std::size_t j = 0; j < joints.size(); ++j) {
      p.position.push_back(a[j] + s * (b[j] - a[j]));
      p.velocity.push_back(ds * (b[j] - a[j]));
    }
    t.samples.push_back(p);
  }
  return t;
}

std::string refusal(RobotCore& core, const JointTrajectory& t) {
  try {
    core.command_trajectory(t);
  } catch (const CommandError& e) {
    return e.what();
  }
  return "";
}

class TrajectoryTest : public ::testing::Test {
 protected:
  TrajectoryTest() : sim_(read_fixture("mobile_drill.urdf"), World{}, {}), core_(sim_) {
    core_.set_model(read_fixture("mobile_drill.urdf"), 3);
    run_cycles(core_, 200);
  }
  double position(const std::string& joint) {
    const RobotState s = core_.state();
    return s.position[hw_index(s, joint)];
  }
  /// Cycles until the trajectory is no longer executing (bounded); returns the progress.
  TrajectoryProgress run_to_end(int max_cycles) {
    for (int i = 0; i < max_cycles; ++i) {
      core_.cycle();
      const TrajectoryProgress p = core_.state().trajectory;
      if (p.sequence != 0 && p.state != TrajectoryState::kExecuting) {
        return p;
      }
    }
    return core_.state().trajectory;
  }
  SimHardware sim_;
  RobotCore core_;
};

TEST_F(TrajectoryTest, CommandsAndModelsSwitchAtTheNextCycleBoundary) {
  core_.command_joints({3, {{"J1_A", DriveMode::kPosition, 0.2, 0, 0, 0, 0}}});
  RobotState s = core_.state();
  EXPECT_EQ(s.owners[hw_index(s, "J1_A")], JointOwner::kHold);  // not yet: the loop has not cycled
  core_.cycle();
  s = core_.state();
  EXPECT_EQ(s.owners[hw_index(s, "J1_A")], JointOwner::kJoint);
  EXPECT_EQ(s.owners[hw_index(s, "J2_A")], JointOwner::kHold);
  core_.command_base({3, 0.1, 0, 0});
  core_.cycle();
  s = core_.state();
  EXPECT_EQ(s.owners[hw_index(s, "J_wheel_fl")], JointOwner::kBase);
  EXPECT_EQ(s.owners[hw_index(s, "J1_A")], JointOwner::kJoint);
  // The ownership record names the controllers.
  bool found = false;
  for (const auto& [joint, controller] : core_.ownership()) {
    if (joint == "J_steer_fl") {
      EXPECT_EQ(controller, "base_velocity");
      found = true;
    }
  }
  EXPECT_TRUE(found);
  // A new model is prepared by set_model() and switched in by the next cycle, holding.
  core_.set_model(read_fixture("mobile_drill.urdf"), 4);
  EXPECT_EQ(core_.state().model_version, 3u);
  core_.cycle();
  s = core_.state();
  EXPECT_EQ(s.model_version, 4u);
  for (auto owner : s.owners) {
    EXPECT_EQ(owner, JointOwner::kHold);
  }
}

TEST_F(TrajectoryTest, ArmTrajectoryIsTrackedClosedLoop) {
  const std::vector<std::string> joints{"J1_A", "J2_A", "J3_A", "J4_B", "J5_B", "J6_B"};
  std::vector<double> a, b;
  for (const auto& j : joints) {
    a.push_back(position(j));
  }
  b = {0.6, 0.5, -0.7, 0.4, -0.5, 0.8};
  core_.command_trajectory(rest_to_rest(3, joints, a, b, 2.0, 40));
  core_.cycle();
  RobotState s = core_.state();
  EXPECT_EQ(s.trajectory.state, TrajectoryState::kExecuting);
  EXPECT_EQ(s.trajectory.request_id, 11u);
  EXPECT_EQ(s.owners[hw_index(s, "J3_A")], JointOwner::kTrajectory);
  const TrajectoryProgress p = run_to_end(6000);
  EXPECT_EQ(p.state, TrajectoryState::kSucceeded) << core_.describe(p);
  EXPECT_DOUBLE_EQ(p.progress, 1.0);
  EXPECT_LT(p.max_joint_error, 0.05);  // drives track position with velocity feed-forward
  for (std::size_t j = 0; j < joints.size(); ++j) {
    EXPECT_NEAR(position(joints[j]), b[j], 0.03) << joints[j];
  }
  run_cycles(core_, 500);  // afterwards the joints hold the final sample
  s = core_.state();
  EXPECT_EQ(s.owners[hw_index(s, "J3_A")], JointOwner::kHold);
  EXPECT_NEAR(position("J3_A"), -0.7, 0.02);
}

TEST_F(TrajectoryTest, BaseFollowsThroughOdometryFeedback) {
  const RobotState s0 = core_.state();
  const std::vector<std::string> joints{kBaseX, kBaseY, kBaseYaw, "J2_A"};
  const std::vector<double> a{s0.odometry.x, s0.odometry.y, s0.odometry.yaw, position("J2_A")};
  const std::vector<double> b{a[0] + 0.6, a[1] + 0.2, a[2] + 0.3, 0.3};
  core_.command_trajectory(rest_to_rest(3, joints, a, b, 4.0, 80));
  const TrajectoryProgress p = run_to_end(12000);
  EXPECT_EQ(p.state, TrajectoryState::kSucceeded) << core_.describe(p);
  const RobotState s = core_.state();
  EXPECT_NEAR(s.odometry.x, b[0], 0.08);
  EXPECT_NEAR(s.odometry.y, b[1], 0.08);
  EXPECT_NEAR(s.odometry.yaw, b[2], 0.08);
  // Odometry is what the base controller closes the loop on; the simulated base truly moved.
  EXPECT_NEAR(sim_.base_pose().translation().x(), b[0], 0.15);
}

TEST_F(TrajectoryTest, SafetyStopAbortsARunningTrajectory) {
  const std::vector<std::string> joints{"J1_A"};
  core_.command_trajectory(rest_to_rest(3, joints, {position("J1_A")}, {1.2}, 3.0, 30));
  run_cycles(core_, 800);
  ASSERT_EQ(core_.state().trajectory.state, TrajectoryState::kExecuting);
  core_.set_safety_stop(true, "estop: front left");
  core_.cycle();
  const TrajectoryProgress p = core_.state().trajectory;
  EXPECT_EQ(p.state, TrajectoryState::kAborted);
  EXPECT_EQ(p.abort, TrajectoryAbort::kSafetyStop);
  EXPECT_NE(core_.describe(p).find("estop: front left"), std::string::npos);
  EXPECT_GT(p.progress, 0.1);
  EXPECT_LT(p.progress, 0.5);
  run_cycles(core_, 1000);
  const RobotState s = core_.state();
  EXPECT_EQ(s.owners[hw_index(s, "J1_A")], JointOwner::kHold);
  EXPECT_NEAR(s.velocity[hw_index(s, "J1_A")], 0.0, 0.01);
  EXPECT_LT(position("J1_A"), 1.0);  // it stopped on the way
  EXPECT_NE(refusal(core_, rest_to_rest(3, joints, {position("J1_A")}, {0.0}, 1.0, 5)).find("safety stop"),
            std::string::npos);
}

TEST_F(TrajectoryTest, AnotherCommandOnItsJointsPreemptsIt) {
  core_.command_trajectory(rest_to_rest(3, {"J1_A", "J2_A"}, {position("J1_A"), position("J2_A")}, {0.8, 0.4}, 3.0, 30));
  run_cycles(core_, 300);
  core_.command_joints({3, {{"J2_A", DriveMode::kPosition, 0.0, 0, 0, 0, 0}}});
  core_.cycle();
  const RobotState s = core_.state();
  EXPECT_EQ(s.trajectory.state, TrajectoryState::kAborted);
  EXPECT_EQ(s.trajectory.abort, TrajectoryAbort::kPreempted);
  EXPECT_EQ(s.owners[hw_index(s, "J2_A")], JointOwner::kJoint);
  EXPECT_EQ(s.owners[hw_index(s, "J1_A")], JointOwner::kHold);
}

TEST_F(TrajectoryTest, BadTrajectoriesAreRefusedWithTheReason) {
  JointTrajectory t = rest_to_rest(3, {"J1_A"}, {0.0}, {0.1}, 1.0, 4);
  t.model_version = 2;
  EXPECT_NE(refusal(core_, t).find("model version 2 refused: current model version is 3"), std::string::npos);
  t = rest_to_rest(3, {"J9_X"}, {0.0}, {0.1}, 1.0, 4);
  EXPECT_NE(refusal(core_, t).find("unknown joint 'J9_X'"), std::string::npos);
  t = rest_to_rest(3, {"J1_A"}, {0.0}, {0.1}, 1.0, 4);
  t.samples[2].time = t.samples[1].time;
  EXPECT_NE(refusal(core_, t).find("strictly increasing"), std::string::npos) << refusal(core_, t);
  t = rest_to_rest(3, {kBaseX, kBaseY}, {0.0, 0.0}, {0.1, 0.0}, 1.0, 4);
  EXPECT_NE(refusal(core_, t).find("base_x, base_y, base_yaw"), std::string::npos);
  t = rest_to_rest(3, {"J1_A"}, {0.0}, {0.1}, 1.0, 4);
  t.samples[1].position.push_back(0.0);
  EXPECT_NE(refusal(core_, t).find("sample 1 has 2 positions"), std::string::npos);
  t = rest_to_rest(3, {"J1_A"}, {0.0}, {0.1}, 1.0, 4);
  t.samples[3].velocity[0] = std::nan("");
  EXPECT_NE(refusal(core_, t).find("non-finite value for 'J1_A'"), std::string::npos);
  EXPECT_EQ(core_.state().trajectory.sequence, 0u);  // nothing reached the loop
}

}  // namespace
}  // namespace concert::robot
