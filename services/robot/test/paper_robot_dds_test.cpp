// The paper's robot over DDS: a model message as modelgen sends it (the wheels' end-effectors
// listed first), and a Cartesian impedance command that must move the drill's tool frame.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model_generation/generator.hpp"
#include "robot_node.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

using namespace std::chrono_literals;
namespace cdds = concert::dds;
namespace fs = std::filesystem;
const fs::path kPublicDb = fs::path(CONCERT_SHARED_DATA) / "concert_resources";
const fs::path kPaperRobot = fs::path(CONCERT_SOURCE_DIR) / "libs" / "simbus" / "examples" / "concert_paper_robot.yaml";

template <class F> bool run_until(RobotCore& core, dds::RobotNode& node, F done, int max_cycles) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  for (int i = 0; i < max_cycles && std::chrono::steady_clock::now() < deadline; ++i) {
    core.cycle();
    node.publish(core.state());
    if (i % 20 == 0) {
      std::this_thread::sleep_for(1ms);
    }
    if (done()) {
      return true;
    }
  }
  return false;
}

TEST(PaperRobotDds, CartesianImpedanceMovesTheDrillToolFrameNotAWheel) {
  const sim::AssemblyBuilder builder({kPublicDb});
  const sim::SimulatedRobot robot = builder.build(kPaperRobot);
  const module_db::ModuleDatabase db = module_db::load_module_database(kPublicDb);
  const model_generation::GeneratedModel generated = model_generation::ModelGenerator(db).generate(robot.tree);

  // The message as modelgen publishes it (libs/model's one conversion).
  model::ModelDescription description = generated.description();
  description.version = 1;
  const msg::RobotModel model = model::dds::to_msg(description, 0);
  std::string drill_frame, wheel_frame;
  for (const auto& e : generated.end_effectors) {
    if (e.kind == model::EndEffectorKind::kDrill) {
      drill_frame = e.frame;
    }
    if (wheel_frame.empty() && e.kind == model::EndEffectorKind::kWheel) {
      wheel_frame = e.frame;
    }
  }
  ASSERT_FALSE(drill_frame.empty());
  ASSERT_FALSE(wheel_frame.empty());
  // As on the paper's robot: the first end-effector of the message is a wheel.
  ASSERT_EQ(model.end_effectors().front().frame(), wheel_frame);

  SimHardware sim(robot, World{}, {});
  RobotCore core(sim);
  cdds::Participant robot_side({.name = "robot"});
  dds::RobotNode node(robot_side, core);
  cdds::Participant client({.name = "client"});
  cdds::Writer<msg::RobotModel> models(client, cdds::topics::robot_model);
  cdds::Writer<msg::CartesianImpedanceCommand> cartesian(client, cdds::topics::cartesian_command);
  ASSERT_TRUE(models.wait_for_readers(1, 10s));
  ASSERT_TRUE(cartesian.wait_for_readers(1, 10s));
  models.write(model);
  ASSERT_TRUE(run_until(core, node, [&] { return core.ready(); }, 100000));
  test::run_cycles(core, 500);
  const RobotState start = core.state();
  ASSERT_EQ(start.end_effector_frame, drill_frame);
  const Eigen::Isometry3d tool0 = sim.link_pose(drill_frame);
  const Eigen::Isometry3d wheel0 = sim.link_pose(wheel_frame);

  // 8 cm forward and 6 cm down, same orientation (robot root frame = the model's world).
  Eigen::Isometry3d target = start.end_effector_pose;
  target.translation() += Eigen::Vector3d(0.08, 0.0, -0.06);
  msg::CartesianImpedanceCommand c;
  c.model_version(1);
  c.source("test");
  c.target().position().x(target.translation().x());
  c.target().position().y(target.translation().y());
  c.target().position().z(target.translation().z());
  const Eigen::Quaterniond q(target.linear());
  c.target().orientation().x(q.x());
  c.target().orientation().y(q.y());
  c.target().orientation().z(q.z());
  c.target().orientation().w(q.w());
  c.stiffness({1500, 1500, 1500, 100, 100, 100});
  c.damping({150, 150, 150, 10, 10, 10});
  c.admittance_axis(255);
  cartesian.write(c);
  ASSERT_TRUE(run_until(
      core, node,
      [&] {
        const RobotState s = core.state();
        return !s.owners.empty() && (s.end_effector_pose.translation() - target.translation()).norm() < 0.01;
      },
      30000))
      << "tool frame at " << core.state().end_effector_pose.translation().transpose() << ", target "
      << target.translation().transpose();
  test::run_cycles(core, 500);
  const RobotState s = core.state();
  EXPECT_LT((s.end_effector_pose.translation() - target.translation()).norm(), 0.01);
  // The simulated drill really moved by the commanded offset; the wheel did not move.
  const Eigen::Vector3d moved = sim.link_pose(drill_frame).translation() - tool0.translation();
  EXPECT_NEAR(moved.x(), 0.08, 0.015);
  EXPECT_NEAR(moved.z(), -0.06, 0.015);
  EXPECT_LT((sim.link_pose(wheel_frame).translation() - wheel0.translation()).norm(), 0.01);
}

}  // namespace
}  // namespace concert::robot
