// The robot service's DDS face: model in, commands in, state/odometry/wrench/status out.
#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <optional>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "robot_conversions.hpp"
#include "robot_node.hpp"
#include "robot_params.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

using namespace std::chrono_literals;
namespace cdds = concert::dds;

// Runs cycles (publishing after each) until `done`, at most `max_cycles` cycles and 20 s of
// wall time (DDS delivery on a loaded machine can take a while).
template <class F> bool run_until(RobotCore& core, dds::RobotNode& node, F done, int max_cycles = 200000) {
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  for (int i = 0; i < max_cycles && std::chrono::steady_clock::now() < deadline; ++i) {
    core.cycle();
    node.publish(core.state());
    if (i % 20 == 0) {
      std::this_thread::sleep_for(1ms);  // let the DDS threads deliver
    }
    if (done()) {
      return true;
    }
  }
  return false;
}

msg::RobotModel model_msg(const std::string& urdf, uint32_t version) {
  msg::RobotModel m;
  m.version(version);
  m.urdf(urdf);
  return m;
}

/// The robot side (simulated drill robot, core, node) and a client participant with a model
/// writer, as each DDS test of the node needs them.
struct NodeRig : ::testing::Test {
  SimHardware sim{test::read_fixture("mobile_drill.urdf"), World{}, {}};
  RobotCore core{sim};
  cdds::Participant robot_side{{.name = "robot"}};
  dds::RobotNode node{robot_side, core};
  cdds::Participant client{{.name = "client"}};
  cdds::Writer<msg::RobotModel> models{client, cdds::topics::robot_model};
};

using RobotNodeDds = NodeRig;

TEST_F(RobotNodeDds, ModelCommandsAndStateOverDds) {
  cdds::Writer<msg::JointCommand> joints(client, cdds::topics::joint_command);
  cdds::Writer<msg::BaseVelocityCommand> base(client, cdds::topics::base_velocity);
  cdds::Reader<msg::JointState> states(client, cdds::topics::joint_state);
  cdds::Reader<msg::Odometry> odometry(client, cdds::topics::odometry);
  cdds::Reader<msg::ServiceStatus> status(client, cdds::topics::status);
  ASSERT_TRUE(models.wait_for_readers(1, 10s));
  ASSERT_TRUE(joints.wait_for_readers(1, 10s));
  ASSERT_TRUE(base.wait_for_readers(1, 10s));

  // The model arrives: the core reconfigures and reports ready at that version.
  models.write(model_msg(test::read_fixture("mobile_drill.urdf"), 7));
  ASSERT_TRUE(run_until(core, node, [&] { return core.ready(); }));
  EXPECT_EQ(core.model_version(), 7u);
  bool ready_seen = false;
  for (int i = 0; i < 100 && !ready_seen; ++i) {
    if (auto s = status.wait(100ms); s && s->service() == "robot" && s->state() == msg::SERVICE_READY) {
      ready_seen = s->model_version() == 7u;
    }
  }
  EXPECT_TRUE(ready_seen);

  // Joint state stream carries every joint.
  auto js = states.wait(5s);
  for (int i = 0; i < 10 && (!js || js->model_version() != 7u); ++i) {
    run_until(core, node, [] { return false; }, 10);
    js = states.wait(1s);
  }
  ASSERT_TRUE(js.has_value());
  EXPECT_EQ(js->name().size(), 14u);
  EXPECT_EQ(js->model_version(), 7u);

  // An unknown joint is refused with a clear error; a stale version too.
  msg::JointCommand bad;
  bad.model_version(7);
  bad.source("test");
  bad.mode(msg::JOINT_POSITION);
  bad.name({"J9_X"});
  bad.position({0.1});
  joints.write(bad);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() >= 1; }));
  EXPECT_NE(node.last_error().find("unknown joint 'J9_X'"), std::string::npos) << node.last_error();
  bad.name({"J1_A"});
  bad.model_version(6);
  joints.write(bad);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() >= 2; }));
  EXPECT_NE(node.last_error().find("current model version is 7"), std::string::npos) << node.last_error();

  // A valid command moves the joint.
  msg::JointCommand good = bad;
  good.model_version(7);
  good.position({0.4});
  joints.write(good);
  EXPECT_TRUE(run_until(core, node, [&] {
    const auto s = core.state();
    return std::abs(s.position[test::hw_index(s, "J1_A")] - 0.4) < 0.01;
  }));

  // Base velocity in, odometry out.
  msg::BaseVelocityCommand drive;
  drive.model_version(7);
  drive.vx(0.2);
  for (int k = 0; k < 20; ++k) {
    base.write(drive);
    run_until(core, node, [] { return false; }, 100);
  }
  std::optional<msg::Odometry> odom;
  while (auto o = odometry.take()) {
    odom = o;
  }
  ASSERT_TRUE(odom.has_value());
  EXPECT_NEAR(odom->vx(), 0.2, 0.02);
  EXPECT_GT(odom->x(), 0.2);
  EXPECT_GT(odom->covariance()[0], 0.0);

  // The safety layer stops the robot: commands are refused until it runs again.
  cdds::Writer<msg::SafetyState> safety(client, cdds::topics::safety_state);
  ASSERT_TRUE(safety.wait_for_readers(1, 10s));
  msg::SafetyState stop;
  stop.mode(msg::SAFETY_STOPPED);
  stop.causes({"estop: wireless"});
  safety.write(stop);
  ASSERT_TRUE(run_until(core, node, [&] { return core.safety_stopped(); }));
  const auto refused_before = node.refused_commands();
  base.write(drive);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() > refused_before; }));
  EXPECT_NE(node.last_error().find("safety stop (estop: wireless)"), std::string::npos) << node.last_error();
  msg::SafetyState run;
  run.mode(msg::SAFETY_RUNNING);
  safety.write(run);
  ASSERT_TRUE(run_until(core, node, [&] { return !core.safety_stopped(); }));

  // A model that does not match the mounted hardware: refused, the old one keeps running.
  const auto refused_now = node.refused_commands();
  models.write(model_msg(test::read_fixture("mobile_three_legs.urdf"), 8));
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() > refused_now; }));
  EXPECT_NE(node.last_error().find("does not match the mounted hardware"), std::string::npos);
  EXPECT_EQ(core.model_version(), 7u);
  EXPECT_TRUE(core.ready());
}

// With a safety timeout (as `concert up` runs it) the robot moves only while it hears the
// safety service: before its first state and after a silence longer than the bound every
// command is refused and the robot holds; a RUNNING state heard again releases it.
TEST(RobotNodeSafetyTimeout, MovesOnlyWhileItHearsTheSafetyService) {
  SimHardware sim{test::read_fixture("mobile_drill.urdf"), World{}, {}};
  RobotCore core{sim};
  cdds::Participant robot_side{{.name = "robot"}};
  dds::NodeParams params;
  params.safety_timeout = 0.3;
  dds::RobotNode node{robot_side, core, params};
  EXPECT_TRUE(core.safety_stopped());
  cdds::Participant client{{.name = "client"}};
  cdds::Writer<msg::RobotModel> models{client, cdds::topics::robot_model};
  cdds::Writer<msg::JointCommand> joints(client, cdds::topics::joint_command);
  cdds::Writer<msg::SafetyState> safety(client, cdds::topics::safety_state);
  ASSERT_TRUE(models.wait_for_readers(1, 10s));
  ASSERT_TRUE(joints.wait_for_readers(1, 10s));
  ASSERT_TRUE(safety.wait_for_readers(1, 10s));
  models.write(model_msg(test::read_fixture("mobile_drill.urdf"), 3));
  ASSERT_TRUE(run_until(core, node, [&] { return core.ready(); }));

  msg::JointCommand move;
  move.model_version(3);
  move.source("test");
  move.mode(msg::JOINT_POSITION);
  move.name({"J1_A"});
  move.position({0.3});
  const auto j1 = [&] {
    const auto s = core.state();
    return s.position[test::hw_index(s, "J1_A")];
  };
  // Not heard yet: refused, the joint stays.
  joints.write(move);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() >= 1; }));
  EXPECT_NE(node.last_error().find("safety service not heard yet"), std::string::npos) << node.last_error();
  EXPECT_NEAR(j1(), 0.0, 0.01);

  // RUNNING heard: released, the command moves the joint.
  msg::SafetyState run;
  run.mode(msg::SAFETY_RUNNING);
  safety.write(run);
  ASSERT_TRUE(run_until(core, node, [&] { return !core.safety_stopped(); }));
  joints.write(move);
  ASSERT_TRUE(run_until(core, node, [&] { return std::abs(j1() - 0.3) < 0.01; }));

  // Silent for longer than the bound: stopped, commands refused naming the silence.
  ASSERT_TRUE(run_until(core, node, [&] { return core.safety_stopped(); }));
  move.position({-0.3});
  const auto refused = node.refused_commands();
  joints.write(move);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() > refused; }));
  EXPECT_NE(node.last_error().find("safety service not heard for"), std::string::npos) << node.last_error();
  run_until(core, node, [] { return false; }, 2000);
  EXPECT_NEAR(j1(), 0.3, 0.01);

  // Heard again, STOPPED: it keeps holding for the safety service's own reason.
  msg::SafetyState stop;
  stop.mode(msg::SAFETY_STOPPED);
  stop.causes({"robot silent 1.2 s"});
  safety.write(stop);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() > refused && core.safety_stopped(); }));
  const auto refused_stop = node.refused_commands();
  joints.write(move);
  ASSERT_TRUE(run_until(core, node, [&] { return node.refused_commands() > refused_stop; }));
  EXPECT_NE(node.last_error().find("robot silent 1.2 s"), std::string::npos) << node.last_error();
  // RUNNING (an operator reset): released.
  safety.write(run);
  ASSERT_TRUE(run_until(core, node, [&] { return !core.safety_stopped(); }));
  joints.write(move);
  EXPECT_TRUE(run_until(core, node, [&] { return std::abs(j1() + 0.3) < 0.01; }));
}

/// Newest TrajectoryStatus of `request` seen so far (drains the reader).
struct StatusLog {
  cdds::Reader<msg::TrajectoryStatus>& reader;
  std::map<uint32_t, msg::TrajectoryStatus> latest;
  std::map<uint32_t, int> executing_updates;
  std::optional<msg::TrajectoryStatus> of(uint32_t request) {
    while (auto s = reader.take()) {
      latest[s->request_id()] = *s;
      if (s->state() == msg::TRAJECTORY_EXECUTING) {
        ++executing_updates[s->request_id()];
      }
    }
    const auto it = latest.find(request);
    return it == latest.end() ? std::nullopt : std::optional<msg::TrajectoryStatus>(it->second);
  }
};

msg::JointTrajectoryCommand ramp(uint32_t request, uint32_t version, const std::string& joint, double from, double to,
                                 double duration) {
  msg::JointTrajectoryCommand c;
  c.request_id(request);
  c.model_version(version);
  c.source("test");
  c.joint_names({joint});
  for (int k = 0; k <= 20; ++k) {
    const double s = k / 20.0;
    msg::JointTrajectorySample p;
    p.time(duration * s);
    p.position({from + (to - from) * (3 * s * s - 2 * s * s * s)});
    p.velocity({(to - from) * 6 * s * (1 - s) / duration});
    c.samples().push_back(p);
  }
  return c;
}

TEST_F(RobotNodeDds, TrajectoriesOverDdsWithProgressResultRefusalAndEstop) {
  cdds::Writer<msg::JointTrajectoryCommand> trajectories(client, cdds::topics::trajectory_command);
  cdds::Writer<msg::SafetyState> safety(client, cdds::topics::safety_state);
  cdds::Reader<msg::TrajectoryStatus> statuses(client, cdds::topics::trajectory_status);
  StatusLog log{statuses, {}, {}};
  ASSERT_TRUE(models.wait_for_readers(1, 10s));
  ASSERT_TRUE(trajectories.wait_for_readers(1, 10s));
  ASSERT_TRUE(safety.wait_for_readers(1, 10s));
  models.write(model_msg(test::read_fixture("mobile_drill.urdf"), 2));
  ASSERT_TRUE(run_until(core, node, [&] { return core.ready(); }));

  // Tracked to the end, with progress on the way.
  trajectories.write(ramp(41, 2, "J2_A", 0.0, 0.6, 1.5));
  ASSERT_TRUE(run_until(core, node, [&] {
    const auto s = log.of(41);
    return s && s->state() != msg::TRAJECTORY_EXECUTING;
  }));
  EXPECT_EQ(log.of(41)->state(), msg::TRAJECTORY_SUCCEEDED) << log.of(41)->reason();
  EXPECT_DOUBLE_EQ(log.of(41)->progress(), 1.0);
  EXPECT_LT(log.of(41)->max_joint_error(), 0.05);
  EXPECT_EQ(log.of(41)->source(), "test");
  EXPECT_GE(log.executing_updates[41], 3);  // 10 Hz progress over 1.5 s
  const RobotState s = core.state();
  EXPECT_NEAR(s.position[test::hw_index(s, "J2_A")], 0.6, 0.03);

  // Refused at once with the reason.
  trajectories.write(ramp(42, 1, "J2_A", 0.6, 0.0, 1.0));
  ASSERT_TRUE(run_until(core, node, [&] { return log.of(42).has_value(); }));
  EXPECT_EQ(log.of(42)->state(), msg::TRAJECTORY_REFUSED);
  EXPECT_NE(log.of(42)->reason().find("current model version is 2"), std::string::npos) << log.of(42)->reason();

  // An e-stop aborts a running trajectory.
  trajectories.write(ramp(43, 2, "J2_A", 0.6, -0.6, 4.0));
  ASSERT_TRUE(run_until(core, node, [&] {
    const auto st = log.of(43);
    return st && st->state() == msg::TRAJECTORY_EXECUTING && st->progress() > 0.1;
  }));
  msg::SafetyState stop;
  stop.mode(msg::SAFETY_STOPPED);
  stop.causes({"estop: front left"});
  safety.write(stop);
  ASSERT_TRUE(run_until(core, node, [&] {
    const auto st = log.of(43);
    return st && st->state() != msg::TRAJECTORY_EXECUTING;
  }));
  EXPECT_EQ(log.of(43)->state(), msg::TRAJECTORY_ABORTED);
  EXPECT_NE(log.of(43)->reason().find("safety stop (estop: front left)"), std::string::npos) << log.of(43)->reason();
  EXPECT_LT(log.of(43)->progress(), 0.9);
}

// A hot swap in standalone mode on a loaded machine: the swap's own model is applied (READY at
// version 2) before the publishing thread has seen the hardware change, whose "hardware
// changed" RECONFIGURING then comes last. Ready again, the node says READY at version 2 again
// (it stood at RECONFIGURING for good: robot_main_test waited 30 s in two fresh-clone CI runs).
TEST_F(RobotNodeDds, ReadyAgainAfterAHardwareChangeSeenLateSaysReady) {
  cdds::Reader<msg::ServiceStatus> status(client, cdds::topics::status);
  node.apply_model(test::read_fixture("mobile_drill.urdf"), 1, "", "hash1", {});
  ASSERT_TRUE(run_until(core, node, [&] { return core.ready(); }));
  // The swap: the loop switches the hardware at its next cycle, the publisher not told yet.
  ASSERT_TRUE(sim.swap_model(test::read_fixture("mobile_three_legs.urdf")));
  core.cycle();
  ASSERT_FALSE(core.state().ready);
  node.apply_model(test::read_fixture("mobile_three_legs.urdf"), 2, "", "hash2", {});  // READY v2 said here
  node.publish(core.state());  // the publisher sees the change now: RECONFIGURING
  ASSERT_TRUE(run_until(core, node, [&] { return core.ready() && core.model_version() == 2u; }));
  // The last status heard: READY at version 2 (the heartbeat repeats whatever stands).
  std::optional<msg::ServiceStatus> last;
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < until &&
         !(last && last->state() == msg::SERVICE_READY && last->model_version() == 2u)) {
    if (auto s = status.wait(100ms); s && s->service() == "robot") last = s;
    node.publish(core.state());
  }
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->state(), msg::SERVICE_READY) << last->message();
  EXPECT_EQ(last->model_version(), 2u);
}

TEST(RobotNode, ToolEndEffectorNeedsAParsableDescription) {
  // A message with only a URDF (no SRDF, no chains): the core picks its default frame.
  EXPECT_EQ(dds::tool_end_effector(model_msg(test::read_fixture("mobile_drill.urdf"), 1)), "");
}

TEST(RobotConversions, JointCommandLengthsAreChecked) {
  msg::JointCommand c;
  c.source("planner");
  c.mode(msg::JOINT_IMPEDANCE);
  c.name({"a", "b"});
  c.position({0.1, 0.2});
  c.stiffness({100.0});
  c.damping({1.0, 1.0});
  try {
    (void)dds::to_core(c);
    FAIL();
  } catch (const CommandError& e) {
    EXPECT_NE(std::string(e.what()).find("'planner'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("'stiffness'"), std::string::npos);
  }
  c.stiffness({100.0, 200.0});
  const JointCommandSet set = dds::to_core(c);
  ASSERT_EQ(set.joints.size(), 2u);
  EXPECT_EQ(set.joints[1].mode, DriveMode::kImpedance);
  EXPECT_DOUBLE_EQ(set.joints[1].stiffness, 200.0);
  EXPECT_DOUBLE_EQ(set.joints[1].velocity, 0.0);
}

TEST(RobotConversions, CartesianAdmittanceAxisIsTheTcpAxisInTheWorld) {
  msg::CartesianImpedanceCommand c;
  c.source("sanding");
  msg::Pose pose;
  msg::Quaternion q;  // 90 degrees about world y: the TCP z axis points along world +x
  q.w(std::sqrt(0.5));
  q.y(std::sqrt(0.5));
  pose.orientation(q);
  c.target(pose);
  c.admittance_axis(2);
  c.admittance_force(25.0);
  c.admittance_gain(0.002);
  const CartesianCommand out = dds::to_core(c);
  ASSERT_TRUE(out.admittance.enabled);
  EXPECT_TRUE(out.admittance.axis.isApprox(Eigen::Vector3d::UnitX(), 1e-9)) << out.admittance.axis.transpose();
  EXPECT_DOUBLE_EQ(out.admittance.force_setpoint, 25.0);
  EXPECT_DOUBLE_EQ(out.admittance.damping, 500.0);
  c.admittance_axis(4);
  EXPECT_THROW((void)dds::to_core(c), CommandError);
  c.admittance_axis(255);
  EXPECT_FALSE(dds::to_core(c).admittance.enabled);
  c.payload_mass(7.5);
  EXPECT_DOUBLE_EQ(dds::to_core(c).payload_mass, 7.5);
  c.payload_mass(-1.0);
  EXPECT_THROW((void)dds::to_core(c), CommandError);
  c.payload_mass(0.0);
  q.w(2.0);
  pose.orientation(q);
  c.target(pose);
  EXPECT_THROW((void)dds::to_core(c), CommandError);
}

TEST(RobotParamsYaml, ShippedConfigListsEveryParameterWithItsDefault) {
  auto doc =
      config::Document::load(std::string(CONCERT_SOURCE_DIR) + "/services/robot/config/robot.yaml");
  (void)dds::read_service_params(doc);
  EXPECT_EQ(doc.keys().size(), 84u);
  EXPECT_TRUE(doc.differences_from_defaults().empty())
      << ::testing::PrintToString(doc.differences_from_defaults());
}

TEST(RobotParamsYaml, ValuesAndClearErrors) {
  const dds::ServiceParams p = dds::parse_service_params(
      "robot: {period: 0.002, end_effector_frame: tcp_E}\n"
      "sim: {initial_positions: {J2_A: 0.3}, floating_base: false, base_position: [1, 2, 0.5]}\n"
      "loop: {real_time: false}\n",
      "p.yaml");
  EXPECT_DOUBLE_EQ(p.robot.period, 0.002);
  EXPECT_DOUBLE_EQ(p.loop.period, 0.002);
  EXPECT_EQ(p.robot.end_effector_frame, "tcp_E");
  EXPECT_DOUBLE_EQ(p.sim.initial_positions.at("J2_A"), 0.3);
  EXPECT_EQ(p.sim.floating_base, std::optional<bool>(false));
  EXPECT_TRUE(p.sim.base_position.isApprox(Eigen::Vector3d(1, 2, 0.5)));
  EXPECT_FALSE(p.loop.real_time);
  auto error_of = [](const std::string& yaml) {
    try {
      (void)dds::parse_service_params(yaml, "p.yaml");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("robot: {perod: 1}").find("robot.perod: unknown key"), std::string::npos);
  EXPECT_EQ(error_of("sim: {armature: heavy}"),
            "p.yaml: sim.armature: expected a number >= 0, got 'heavy' (line 1)");
  EXPECT_NE(error_of("sim: {base_position: [1, 2]}").find("sim.base_position"), std::string::npos);
  EXPECT_EQ(error_of("drives: {}"),
            "p.yaml: drives: unknown key (line 1); known keys: loop, node, robot, sensors, sim");
  EXPECT_NE(error_of("robot: {period: 0}").find("positive"), std::string::npos);
  EXPECT_NE(error_of("robot: [").find("p.yaml"), std::string::npos);
}

}  // namespace
}  // namespace concert::robot
