#include "robot/robot_core.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <thread>

#include "model_fixture.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

using test::hw_index;
using test::read_fixture;
using test::run_cycles;

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

class RobotCoreTest : public ::testing::Test {
 protected:
  RobotCoreTest() : sim_(read_fixture("mobile_drill.urdf"), World{}, {}), core_(sim_) {}
  SimHardware sim_;
  RobotCore core_;
};

TEST_F(RobotCoreTest, NotReadyWithoutAModelAndHoldsTheHardware) {
  EXPECT_FALSE(core_.ready());
  EXPECT_NE(message_of([&] { core_.command_base({0, 0.1, 0, 0}); }).find("not ready"), std::string::npos);
  run_cycles(core_, 300);
  const RobotState s = core_.state();
  EXPECT_NEAR(s.time, 0.299, 1e-9);  // state is read before the cycle's step
  EXPECT_NEAR(s.position[hw_index(s, "J2_A")], 0.0, 0.01);
}

TEST_F(RobotCoreTest, AcceptsAMatchingModelAndFindsArmAndLegs) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  EXPECT_TRUE(core_.ready());
  EXPECT_EQ(core_.model_version(), 1u);
  EXPECT_EQ(core_.arm_joints(), (std::vector<std::string>{"J1_A", "J2_A", "J3_A", "J4_B", "J5_B", "J6_B"}));
  EXPECT_EQ(core_.legs().size(), 4u);
  run_cycles(core_, 10);
  const RobotState s = core_.state();
  EXPECT_EQ(s.end_effector_frame, "tcp");
  EXPECT_TRUE(s.has_base);
  EXPECT_EQ(s.message, "ready at model version 1");
}

// The model as the services hold it (libs/model): the end-effector is its tool and the legs
// its leg chains, by role; the hardware is the simulation of the same model.
TEST(RobotCoreModel, ReadsTheToolAndTheLegsOfTheModelByRole) {
  const auto model = concert::testing::robot_model(std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml", 3);
  SimHardware sim(model->description().urdf, World{}, {});
  RobotCore core(sim);
  core.set_model(model);
  ASSERT_TRUE(core.ready());
  EXPECT_EQ(core.model_version(), 3u);
  EXPECT_EQ(core.arm_joints(), model->arm().joints);
  ASSERT_EQ(core.legs().size(), model->legs().size());
  for (std::size_t i = 0; i < core.legs().size(); ++i) {
    EXPECT_EQ(core.legs()[i].steering_joint, model->legs()[i].steering_joint);
    EXPECT_EQ(core.legs()[i].wheel_joint, model->legs()[i].wheel_joint);
    EXPECT_DOUBLE_EQ(core.legs()[i].wheel_radius, model->legs()[i].wheel_radius);
  }
  run_cycles(core, 10);
  EXPECT_EQ(core.state().end_effector_frame, model->tool().frame);
  EXPECT_TRUE(core.state().has_base);
  // An older version is refused; the running one stays.
  EXPECT_NE(message_of([&] { core.set_model(concert::testing::robot_model(
                               std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml", 2)); })
                .find("older than the current version 3"),
            std::string::npos);
  EXPECT_EQ(core.model_version(), 3u);
}

// A leg chain the model cannot give (here: its wheel end-effector dropped) refuses the model
// with the chain's name, as nav refuses it; the robot does not guess the legs by their axes.
TEST(RobotCoreModel, RefusesAModelWhoseLegChainHasNoWheel) {
  const std::string assembly = std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml";
  const auto good = concert::testing::robot_model(assembly, 1);
  SimHardware sim(good->description().urdf, World{}, {});
  RobotCore core(sim);
  core.set_model(good);
  ASSERT_TRUE(core.ready());
  concert::model::ModelDescription d = good->description();
  d.version = 2;
  const auto wheel = std::find_if(d.end_effectors.begin(), d.end_effectors.end(), [](const auto& e) {
    return e.kind == concert::model::EndEffectorKind::kWheel;
  });
  ASSERT_NE(wheel, d.end_effectors.end());
  const std::string chain = wheel->chain;
  d.end_effectors.erase(wheel);
  const std::string msg = message_of([&] { core.set_model(concert::model::RobotModel::build(d)); });
  EXPECT_NE(msg.find("model version 2 refused"), std::string::npos) << msg;
  EXPECT_NE(msg.find("leg chain " + chain), std::string::npos) << msg;
  EXPECT_EQ(core.model_version(), 1u);  // the last good model stays
  EXPECT_TRUE(core.ready());
}

TEST_F(RobotCoreTest, RefusesModelsThatDoNotMatchTheMountedHardware) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  const std::string msg = message_of([&] { core_.set_model(read_fixture("mobile_three_legs.urdf"), 2); });
  EXPECT_NE(msg.find("does not match the mounted hardware"), std::string::npos) << msg;
  EXPECT_NE(msg.find("J_steer_rr"), std::string::npos) << msg;
  EXPECT_NE(msg.find("J_wheel_rr"), std::string::npos) << msg;
  EXPECT_EQ(core_.model_version(), 1u);  // the last good model stays
  EXPECT_TRUE(core_.ready());
  EXPECT_NE(message_of([&] { core_.set_model("<robot", 3); }).find("model version 3 refused"), std::string::npos);
  EXPECT_NE(message_of([&] { core_.set_model(read_fixture("mobile_drill.urdf"), 0); }).find("older"),
            std::string::npos);
}

TEST_F(RobotCoreTest, RefusesUnknownJointsStaleVersionsAndBadValues) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 4);
  JointCommandSet cmd{4, {{"J9_X", DriveMode::kPosition, 0.1, 0, 0, 0, 0}}};
  std::string msg = message_of([&] { core_.command_joints(cmd); });
  EXPECT_NE(msg.find("unknown joint 'J9_X'"), std::string::npos) << msg;
  cmd.joints[0].joint = "J1_A";
  cmd.model_version = 3;
  msg = message_of([&] { core_.command_joints(cmd); });
  EXPECT_NE(msg.find("model version 3 refused: current model version is 4"), std::string::npos) << msg;
  cmd.model_version = 4;
  cmd.joints[0].position = std::nan("");
  EXPECT_NE(message_of([&] { core_.command_joints(cmd); }).find("non-finite"), std::string::npos);
  cmd.joints[0].position = 0.1;
  cmd.joints.push_back(cmd.joints[0]);
  EXPECT_NE(message_of([&] { core_.command_joints(cmd); }).find("twice"), std::string::npos);
  CartesianCommand cart;
  cart.model_version = 4;
  cart.frame = "wheel_fl";
  EXPECT_NE(message_of([&] { core_.command_cartesian(cart); }).find("not the end-effector frame"), std::string::npos);
}

TEST_F(RobotCoreTest, PositionAndVelocityLimitsAreEnforced) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  // J2_A: position limits [-2, 2] rad, velocity limit 1.5 rad/s. Ask for 2.5 rad.
  core_.command_joints({1, {{"J1_A", DriveMode::kPosition, 2.5, 0, 0, 0, 0}}});
  double max_speed = 0.0;
  for (int i = 0; i < 3000; ++i) {
    core_.cycle();
    const RobotState s = core_.state();
    max_speed = std::max(max_speed, std::abs(s.velocity[hw_index(s, "J1_A")]));
  }
  const RobotState s = core_.state();
  EXPECT_LE(s.position[hw_index(s, "J1_A")], 2.9 + 0.01);  // J1_A upper limit 2.9 rad
  EXPECT_NEAR(s.position[hw_index(s, "J1_A")], 2.5, 0.01);
  EXPECT_LE(max_speed, 1.5 * 1.05);
  EXPECT_GE(max_speed, 1.5 * 0.8);
  // Beyond the position limit: clamped to it.
  core_.command_joints({1, {{"J2_A", DriveMode::kPosition, 2.5, 0, 0, 0, 0}}});
  run_cycles(core_, 3000);
  const RobotState s2 = core_.state();
  EXPECT_NEAR(s2.position[hw_index(s2, "J2_A")], 2.0, 0.03);
  // Velocity mode: clamped at 2.5 rad/s for J4_B.
  core_.command_joints({1, {{"J4_B", DriveMode::kVelocity, 0, 10.0, 0, 0, 0}}});
  run_cycles(core_, 500);
  const RobotState s3 = core_.state();
  EXPECT_NEAR(s3.velocity[hw_index(s3, "J4_B")], 2.5, 0.1);
}

TEST_F(RobotCoreTest, EffortCommandsSaturateAtTheTorqueLimit) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  core_.command_joints({1, {{"J4_B", DriveMode::kEffort, 0, 0, 500.0, 0, 0}}});
  run_cycles(core_, 3);
  const RobotState s = core_.state();
  EXPECT_NEAR(s.effort[hw_index(s, "J4_B")], 40.0, 1e-6);
}

// A torque-level command pushing a joint outward (a Cartesian target it cannot reach does the
// same): the position guard stops it short of its limit, where without the guard it passes the
// limit by more than the safety service's 0.02 rad tolerance.
TEST(RobotCore, ThePositionGuardStopsATorquePushShortOfTheLimit) {
  const auto farthest = [](double margin) {
    SimHardware sim(read_fixture("arm_drill.urdf"), World{}, [] {
      SimParams p;
      p.initial_positions = {{"J1_A", 2.85}};
      return p;
    }());
    RobotParams params;
    params.position_guard_margin = margin;
    RobotCore core(sim, params);
    core.set_model(read_fixture("arm_drill.urdf"), 1);
    run_cycles(core, 100);
    // J1_A: vertical axis (no gravity on it), limits +-2.9 rad, peak torque 150 N m.
    core.command_joints({1, {{"J1_A", DriveMode::kEffort, 0, 0, 30.0, 0, 0}}});
    double most = -1e9;
    for (int k = 0; k < 3000; ++k) {
      core.cycle();
      const RobotState s = core.state();
      most = std::max(most, s.position[hw_index(s, "J1_A")]);
    }
    return most;
  };
  const double guarded = farthest(0.03);
  EXPECT_LT(guarded, 2.9) << "guarded";
  EXPECT_GT(guarded, 2.9 - 0.03) << "the push reaches into the margin";
  const double unguarded = farthest(0.0);
  EXPECT_GT(unguarded, 2.9 + 0.02) << "without the guard the push passes the limit";
}

TEST_F(RobotCoreTest, GravityCompensationFloatsTheArm) {
  test::SimulatedArm arm({{"J2_A", 0.5}, {"J3_A", 0.6}}, 200);
  RobotCore& core = arm.core;
  // Position hold has gravity feed-forward: no sag (g / kp would be ~0.02 rad here).
  const RobotState held = core.state();
  EXPECT_NEAR(held.position[hw_index(held, "J2_A")], 0.5, 2e-3);
  core.command_gravity_compensation(1);
  run_cycles(core, 1000);
  const RobotState s = core.state();
  EXPECT_EQ(s.owners[hw_index(s, "J2_A")], JointOwner::kGravityCompensation);
  EXPECT_NEAR(s.position[hw_index(s, "J2_A")], 0.5, 5e-3);
  EXPECT_NEAR(s.position[hw_index(s, "J3_A")], 0.6, 5e-3);
  // Torques are the model's gravity torques (not position-control torques).
  EXPECT_GT(std::abs(s.effort[hw_index(s, "J2_A")]), 5.0);
}

TEST_F(RobotCoreTest, SafetyStopHoldsAndRefusesCommands) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  core_.command_joints({1, {{"J1_A", DriveMode::kVelocity, 0, 1.0, 0, 0, 0}}});
  test::drive_base(core_, {1, 0.3, 0.0, 0.0}, 400);
  core_.set_safety_stop(true, "estop: wireless");
  EXPECT_TRUE(core_.safety_stopped());
  const std::string msg = message_of([&] { core_.command_base({1, 0.3, 0, 0}); });
  EXPECT_NE(msg.find("safety stop (estop: wireless)"), std::string::npos) << msg;
  run_cycles(core_, 1000);
  RobotState s = core_.state();
  EXPECT_NEAR(s.velocity[hw_index(s, "J1_A")], 0.0, 0.01);
  EXPECT_NEAR(s.odometry.vx, 0.0, 0.01);
  for (auto owner : s.owners) {
    EXPECT_EQ(owner, JointOwner::kHold);
  }
  core_.set_safety_stop(false);
  EXPECT_NO_THROW(core_.command_base({1, 0.1, 0, 0}));
}

// The legs' I^2 t foldback (model::folded_back_torque): a base driven into a wall keeps its
// wheels pushing; with the wheels' continuous torque in the limits table their drives fold back
// and their RMS torque never reaches the safety layer's sustained bound, while the arm's
// joints keep their peak torque (a yielding arm joint moves the tool).
TEST(RobotCore, WheelsPushingAWallFoldTheirTorqueBackTheArmDoesNot) {
  const std::vector<std::string> wheels = {"J_wheel_fl", "J_wheel_fr", "J_wheel_rl", "J_wheel_rr"};
  const auto push = [&](const model::LimitsTable& limits, double* rms_max) {
    World world;
    WorldShape wall;
    wall.name = "wall";
    wall.size = {0.2, 4.0, 1.0};
    wall.position = {1.2, 0.0, 0.5};
    world.walls.push_back(wall);
    SimHardware sim(read_fixture("mobile_drill.urdf"), world, {});
    RobotCore core(sim);
    core.set_model(read_fixture("mobile_drill.urdf"), 1, "", limits);
    run_cycles(core, 200);
    std::vector<model::ThermalLoad> measured(wheels.size());  // safety's model, on the drives' report
    *rms_max = 0.0;
    const double dt = core.params().period;
    for (int k = 0; k < 25000; ++k) {  // 25 s at 0.3 m/s: the wall is 0.5 m ahead
      if (k % 100 == 0) core.command_base({1, 0.3, 0.0, 0.0});
      core.cycle();
      const RobotState s = core.state();
      for (std::size_t w = 0; w < wheels.size(); ++w)
        *rms_max = std::max(*rms_max, measured[w].add(s.effort[hw_index(s, wheels[w])], dt));
    }
    return core.state();
  };
  double rms_free = 0.0;
  const RobotState free = push({}, &rms_free);
  ASSERT_GT(rms_free, 5.0) << "the wheels push the wall";
  EXPECT_DOUBLE_EQ(free.torque_limit[hw_index(free, "J_wheel_fl")], 60.0);  // the URDF's effort
  // The wheels rated for 60 % of that push continuously (peak 60 N m as in the URDF); J2_A too.
  const double continuous = 0.6 * rms_free;
  std::vector<model::JointLimits> rows;
  for (const auto& w : wheels) rows.push_back({w, "B", -1e9, 1e9, 10.0, 60.0, continuous});
  rows.push_back({"J2_A", "A", -2.0, 2.0, 1.5, 150.0, 1.0});
  const model::LimitsTable limits(rows, "test");
  double rms_max = 0.0;
  const RobotState folded = push(limits, &rms_max);
  EXPECT_GT(rms_free, model::sustained_torque_bound(limits.at("J_wheel_fl"), 0.1));
  EXPECT_LE(rms_max, continuous * 1.02) << "safety's bound is " << continuous * 1.1;
  for (const auto& w : wheels) EXPECT_NEAR(folded.torque_limit[hw_index(folded, w)], continuous, 1e-6) << w;
  EXPECT_DOUBLE_EQ(folded.torque_limit[hw_index(folded, "J2_A")], 150.0) << "the arm keeps its peak";
  std::cout << "wheels pushing the wall: RMS " << rms_free << " N m without foldback, " << rms_max
            << " with (continuous " << continuous << ")\n";
}

// What DDS clients use for teaching mode (README): no stiffness, no damping.
CartesianCommand gravity_compensation(double payload_mass = 0.0) {
  CartesianCommand c;
  c.model_version = 1;
  c.stiffness.setZero();
  c.damping.setZero();
  c.payload_mass = payload_mass;
  return c;
}

TEST(RobotCore, CartesianWithZeroGainsIsGravityCompensation) {
  test::SimulatedArm arm({{"J2_A", 0.5}, {"J3_A", 0.6}}, 200);
  RobotCore& core = arm.core;
  const CartesianCommand c = gravity_compensation();
  core.command_cartesian(c);  // target pose irrelevant without stiffness
  run_cycles(core, 1000);
  const RobotState s = core.state();
  EXPECT_NEAR(s.position[hw_index(s, "J2_A")], 0.5, 5e-3);
  EXPECT_NEAR(s.position[hw_index(s, "J3_A")], 0.6, 5e-3);
  EXPECT_EQ(s.owners[hw_index(s, "J2_A")], JointOwner::kCartesian);
}

// A payload at the TCP (a 3 kg weight hung there in MuJoCo): told its mass, the Cartesian
// gravity compensation holds the arm where it was; not told, the arm falls under the weight.
TEST(RobotCore, CartesianPayloadMassIsGravityCompensated) {
  auto joints_after = [](double told_mass) {
    test::SimulatedArm arm({{"J2_A", 0.5}, {"J3_A", 0.6}}, 200);
    RobotCore& core = arm.core;
    core.command_cartesian(gravity_compensation(told_mass));
    const std::string tcp = core.state().end_effector_frame;
    for (int k = 0; k < 1000; ++k) {
      const Eigen::Isometry3d T = arm.sim.link_pose(tcp);
      arm.sim.set_external_force(tcp, Eigen::Vector3d(0.0, 0.0, -3.0 * 9.81), T.translation());
      core.cycle();
    }
    const RobotState s = core.state();
    return Eigen::Vector2d(s.position[hw_index(s, "J2_A")], s.position[hw_index(s, "J3_A")]);
  };
  const Eigen::Vector2d told = joints_after(3.0);
  EXPECT_NEAR(told.x(), 0.5, 5e-3);
  EXPECT_NEAR(told.y(), 0.6, 5e-3);
  const Eigen::Vector2d untold = joints_after(0.0);
  EXPECT_GT((untold - Eigen::Vector2d(0.5, 0.6)).norm(), 0.05) << untold.transpose();
}

TEST(RobotCore, CartesianPayloadMassMustBeFiniteAndNotNegative) {
  test::SimulatedArm arm({}, 10);
  CartesianCommand c;
  c.model_version = 1;
  c.payload_mass = -1.0;
  EXPECT_NE(message_of([&] { arm.core.command_cartesian(c); }).find("payload_mass"), std::string::npos);
  c.payload_mass = std::nan("");
  EXPECT_NE(message_of([&] { arm.core.command_cartesian(c); }).find("payload_mass"), std::string::npos);
  c.payload_mass = 2.0;
  EXPECT_EQ(message_of([&] { arm.core.command_cartesian(c); }), "");
}

TEST_F(RobotCoreTest, CommandsAndModelsFromAnotherThreadWhileCycling) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  std::atomic<bool> finished{false};
  std::atomic<int> accepted{0};
  std::atomic<int> bumps{0};
  std::thread client([&] {
    for (int k = 0; k < 300; ++k) {
      try {
        core_.command_base({core_.model_version(), 0.1, 0.0, 0.0});
        core_.command_joints({core_.model_version(), {{"J1_A", DriveMode::kPosition, 0.001 * k, 0, 0, 0, 0}}});
        if (k % 100 == 50) {
          core_.set_model(read_fixture("mobile_drill.urdf"), core_.model_version() + 1);
          ++bumps;
        }
        (void)core_.state();
        ++accepted;
      } catch (const CommandError&) {
        // A version bump between reading model_version() and commanding: refused, fine.
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    finished = true;
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (int i = 0; i < 1000000 && !finished.load() && std::chrono::steady_clock::now() < deadline; ++i) {
    core_.cycle();
  }
  client.join();
  EXPECT_GE(accepted.load(), 200);
  EXPECT_GE(bumps.load(), 2);
  EXPECT_EQ(core_.model_version(), 1u + static_cast<unsigned>(bumps.load()));
  EXPECT_TRUE(core_.ready());
}

TEST_F(RobotCoreTest, HotSwapThenReconfigureToTheNewModel) {
  core_.set_model(read_fixture("mobile_drill.urdf"), 1);
  run_cycles(core_, 100);
  // Replace the drill by the sanding tool: same joints, new links.
  sim_.swap_model(read_fixture("mobile_sander.urdf"));
  run_cycles(core_, 10);
  EXPECT_FALSE(core_.ready());
  EXPECT_NE(core_.state().message.find("hardware changed"), std::string::npos);
  EXPECT_NE(message_of([&] { core_.command_base({1, 0.1, 0, 0}); }).find("not ready"), std::string::npos);
  core_.set_model(read_fixture("mobile_sander.urdf"), 2);
  EXPECT_TRUE(core_.ready());
  run_cycles(core_, 10);
  EXPECT_EQ(core_.state().model_version, 2u);
  // Remove a leg: the old model no longer matches, the new one does.
  sim_.swap_model(read_fixture("mobile_three_legs.urdf"));
  run_cycles(core_, 10);
  EXPECT_FALSE(core_.ready());
  EXPECT_THROW(core_.set_model(read_fixture("mobile_sander.urdf"), 3), ModelMismatchError);
  core_.set_model(read_fixture("mobile_three_legs.urdf"), 3);
  EXPECT_TRUE(core_.ready());
  EXPECT_EQ(core_.legs().size(), 3u);
  run_cycles(core_, 500);
  // The robot held still through both swaps.
  const RobotState s = core_.state();
  EXPECT_NEAR(s.position[hw_index(s, "J2_A")], 0.0, 0.02);
}

}  // namespace
}  // namespace concert::robot
