// The robot core on the ethercat backend: the demo's drilling robot behind the virtual ring
// (libs/ethercat: its drives are the MuJoCo robot of libs/sim), the model generated from the
// scan the master read, as the discovery and modelgen services make it. The joints are bound
// to the drive boards by the robot_ids of the model's controller configuration, the core runs
// the model, and a joint command moves the robot behind the ring; a model of another robot is
// refused naming the joint and the robot_id no board has.

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "concert/ethercat/ethercat_hardware.hpp"
#include "concert/ethercat/robot_on_ring.hpp"
#include "concert/ethercat/virtual_ring.hpp"
#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/reconstruction.hpp"
#include "concert/topology/scan_io.hpp"
#include "robot/robot_core.hpp"
#include "test_data.hpp"

namespace concert::robot {
namespace {

const std::string kAssembly = std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml";
const std::string kProcessData = std::string(CONCERT_SOURCE_DIR) + "/data/module_db/process_data.yaml";

// What the discovery and modelgen services make of a scan.
std::shared_ptr<const model::RobotModel> model_of(const topology::EscScan& scan, uint64_t version) {
  const module_db::ModuleDatabase db = module_db::load_module_database(test_data::kProjectDb);
  const topology::ModuleTree tree = topology::discover(scan, topology::EscCatalog::load(test_data::kProjectDb));
  model::ModelDescription d = model_generation::ModelGenerator(db).generate(tree).description();
  d.version = version;
  return model::RobotModel::build(d);
}

TEST(EthercatBackend, RunsTheModelGeneratedFromTheRingsScan) {
  sim::SimParams quiet;
  quiet.sensors.enabled = false;
  const sim::AssemblyBuilder builder({test_data::kProjectDb});
  const sim::SimulatedRobot robot = builder.build(kAssembly);
  sim::SimHardware behind(robot, world::World{}, quiet);
  const ethercat::ProcessDataCatalog pd = ethercat::ProcessDataCatalog::load(kProcessData);
  ethercat::VirtualRing ring(simbus::load_assembly(kAssembly), topology::EscCatalog::load(test_data::kProjectDb),
                             ethercat::RingParams{}, &pd);
  ethercat::RobotOnRing app(behind, robot, *pd.find(21));
  ring.set_application([&app](std::span<ethercat::BoardIo> boards, uint64_t now) { app.exchange(boards, now); });
  uint64_t now = 0;
  ethercat::LoopbackLink link([&](std::span<const uint8_t> f) { return ring.process(f, now += 1'000'000); });
  ethercat::EthercatHardware hw(link, pd,
                                ethercat::MasterParams{.frame_timeout = std::chrono::microseconds(1000),
                                                       .state_poll_interval = std::chrono::microseconds(0)});

  // The model from the master's scan carries each joint's robot_id: the simulator's own.
  const auto model = model_of(hw.scan().scan(), 1);
  const auto ids = ethercat::joint_robot_ids(model->description().config_yaml);
  ASSERT_EQ(ids.size(), robot.joint_robot_ids.size());
  for (const auto& [joint, id] : ids) EXPECT_EQ(id, robot.joint_robot_ids.at(joint)) << joint;

  RobotParams params;
  RobotCore core(hw, params);
  hw.prepare_joints(ids);
  EXPECT_EQ(hw.mounted().joint_names.size(), ids.size());
  EXPECT_EQ(hw.generation(), 0u);  // prepared, not yet switched: the loop switches
  core.set_model(model);
  for (int i = 0; i < 50; ++i) core.cycle();
  ASSERT_TRUE(core.ready());
  EXPECT_EQ(hw.generation(), 1u);
  // The same binding again (the next version of the same robot's model) changes nothing.
  hw.prepare_joints(ids);
  core.cycle();
  EXPECT_EQ(hw.generation(), 1u);

  // The elbow (robot_id 52) 0.3 rad on: the robot behind the ring moves.
  std::string elbow;
  for (const auto& [joint, id] : ids) {
    if (id == 52) elbow = joint;
  }
  ASSERT_FALSE(elbow.empty());
  const auto position = [&](const std::string& joint) {
    hardware::HardwareState s;
    behind.read(s);
    for (std::size_t j = 0; j < behind.joint_names().size(); ++j) {
      if (behind.joint_names()[j] == joint) return s.position[j];
    }
    ADD_FAILURE() << "no joint " << joint;
    return 0.0;
  };
  const double from = position(elbow);
  JointCommandSet cmd;
  cmd.model_version = 1;
  cmd.joints.push_back({.joint = elbow, .mode = DriveMode::kPosition, .position = from + 0.3});
  core.command_joints(cmd);
  for (int i = 0; i < 1500; ++i) core.cycle();
  EXPECT_GT(position(elbow) - from, 0.15);
  EXPECT_EQ(hw.cycle_faults(), 0u);
  // What the core reports is what the ring's drives reported.
  const RobotState state = core.state();
  for (std::size_t j = 0; j < state.joint_names.size(); ++j) {
    if (state.joint_names[j] == elbow) {
      EXPECT_NEAR(state.position[j], position(elbow), 2e-3);
    }
  }

  // Another robot's model: its elbow's board has robot_id 77, which this ring has not.
  // Refused naming the joint; the running binding stays.
  std::ifstream in(kAssembly);
  std::stringstream text;
  text << in.rdbuf();
  std::string other_text = text.str();
  const auto at = other_text.find("robot_id: 52}");
  ASSERT_NE(at, std::string::npos);
  other_text.replace(at, 13, "robot_id: 77}");
  const sim::SimulatedRobot other = builder.build_from_text(other_text, "other_robot.yaml");
  const auto other_ids = ethercat::joint_robot_ids(model_of(other.scan, 2)->description().config_yaml);
  try {
    hw.prepare_joints(other_ids);
    ADD_FAILURE() << "another robot's joints were bound";
  } catch (const hardware::HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("joint '" + elbow + "': no board with robot_id 77 on the ring"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(hw.mounted().generation, 1u);

  // The configuration and the model must name the same joints.
  std::vector<std::string> modelled;
  for (const model::JointLimits& j : model->description().joints) modelled.push_back(j.name);
  EXPECT_EQ(ethercat::model_binding(model->description().config_yaml, modelled), ids);
  modelled.pop_back();
  try {
    (void)ethercat::model_binding(model->description().config_yaml, modelled);
    ADD_FAILURE() << "a configuration with a joint the model has not was taken";
  } catch (const hardware::HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("of the controller configuration is not in the model"), std::string::npos)
        << e.what();
  }
  modelled.push_back("J_extra");
  modelled.push_back(model->description().joints.back().name);
  try {
    (void)ethercat::model_binding(model->description().config_yaml, modelled);
    ADD_FAILURE() << "a model with a joint the configuration has not was taken";
  } catch (const hardware::HardwareError& e) {
    EXPECT_EQ(std::string(e.what()), "joint 'J_extra' of the model is not in its controller configuration");
  }

  // A configuration without robot_ids (a hand-made tree) names the joint.
  EXPECT_THROW(ethercat::joint_robot_ids("joints:\n  - {name: J1_A}\n"), hardware::HardwareError);
  try {
    (void)ethercat::joint_robot_ids("joints:\n  - {name: J1_A, robot_id: -1}\n");
  } catch (const hardware::HardwareError& e) {
    EXPECT_NE(std::string(e.what()).find("joints[0] 'J1_A': no robot_id"), std::string::npos) << e.what();
  }
}

// The real CONCERT robot's scan (18 ESCs, ../shared/data): the model made from it binds its 14
// joints to the 14 drive boards (ESC type 21) of that scan, one board each.
TEST(EthercatBackend, TheRealScansModelBindsEveryJointToOneOfItsDriveBoards) {
  const std::string db = std::string(CONCERT_SHARED_DATA) + "/concert_resources";
  const topology::EscScan scan = topology::load_scan(std::string(CONCERT_SHARED_DATA) +
                                                     "/ethercat/concert_robot_18slaves.yaml");
  const topology::ModuleTree tree = topology::discover(scan, topology::EscCatalog::load(db));
  const auto generated = model_generation::ModelGenerator(module_db::load_module_database(db)).generate(tree);
  std::set<int32_t> drive_boards;
  for (const topology::EscSlave& s : scan.slaves) {
    if (s.esc_type == 21) drive_boards.insert(s.robot_id);
  }
  ASSERT_EQ(drive_boards.size(), 14u);
  const auto ids = ethercat::joint_robot_ids(generated.config_yaml);
  EXPECT_EQ(ids.size(), generated.joints.size());
  std::set<int32_t> bound;
  for (const auto& [joint, id] : ids) {
    EXPECT_TRUE(drive_boards.count(id)) << joint << " has robot_id " << id << ", no drive board of the scan";
    EXPECT_TRUE(bound.insert(id).second) << "two joints on robot_id " << id;
  }
  EXPECT_EQ(bound, drive_boards);
}

}  // namespace
}  // namespace concert::robot
