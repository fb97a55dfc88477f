// The demo's drilling robot behind the virtual ring: commands sent as process data move the
// MuJoCo robot exactly as the same commands given to the sim backend directly.

#include <gtest/gtest.h>

#include <cmath>

#include "concert/ethercat/ethercat_hardware.hpp"
#include "concert/ethercat/master.hpp"
#include "concert/ethercat/robot_on_ring.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "test_data.hpp"

namespace concert::ethercat {
namespace {

const std::string kAssembly = std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml";
const std::string kProcessData = std::string(CONCERT_SOURCE_DIR) + "/data/module_db/process_data.yaml";

sim::SimParams quiet() {
  sim::SimParams p;
  p.sensors.enabled = false;
  return p;
}

TEST(RobotOnRing, MovesTheSimulatedRobotAsTheSimBackendDoes) {
  const sim::AssemblyBuilder builder({test_data::kProjectDb});
  const sim::SimulatedRobot robot = builder.build(kAssembly);
  sim::SimHardware direct(robot, world::World{}, quiet());
  sim::SimHardware ringed(robot, world::World{}, quiet());
  const ProcessDataCatalog pd = ProcessDataCatalog::load(kProcessData);
  const topology::EscCatalog catalog = topology::EscCatalog::load(test_data::kProjectDb);
  VirtualRing ring(simbus::load_assembly(kAssembly), catalog, RingParams{}, &pd);
  RobotOnRing app(ringed, robot, *pd.find(21));
  ring.set_application([&app](std::span<BoardIo> boards, uint64_t now) { app.exchange(boards, now); });
  uint64_t now = 0;
  LoopbackLink link([&](std::span<const uint8_t> f) { return ring.process(f, now += 1'000'000); });
  Master master(link, MasterParams{.frame_timeout = std::chrono::microseconds(1000),
                                   .state_poll_interval = std::chrono::microseconds(0)});
  const ScanReport report = master.scan();
  ProcessImage image = master.map_process_data(report);
  for (const auto s : {esc::AlState::kPreOp, esc::AlState::kSafeOp, esc::AlState::kOp}) {
    master.request_state(report, s);
  }

  // Each joint's board in the master's image, by robot_id.
  const auto& joints = direct.joint_names();
  ASSERT_EQ(joints, ringed.joint_names());
  std::vector<const ProcessImageSlave*> board(joints.size(), nullptr);
  for (std::size_t j = 0; j < joints.size(); ++j) {
    for (const ProcessImageSlave& s : image.slaves) {
      if (report.slaves[static_cast<std::size_t>(s.position - 1)].sii.robot_id == robot.joint_robot_ids.at(joints[j])) {
        board[j] = &s;
      }
    }
    ASSERT_NE(board[j], nullptr) << joints[j];
  }
  EXPECT_TRUE(app.unmatched().empty());

  // The direct simulation catches up with the steps the ring made while boards held (SAFE-OP).
  hardware::HardwareState start;
  direct.read(start);
  std::vector<hardware::DriveCommand> hold(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) {
    hold[j].mode = hardware::DriveMode::kPosition;
    hold[j].position = start.position[j];
  }
  for (uint64_t i = 0; i < app.steps(); ++i) {
    direct.write(hold);
    direct.step(0.001);
  }

  // The elbow (robot_id 52) to +0.3 rad from where it is, every other joint held, 1.5 s.
  const DriveCodec codec(*pd.find(21));
  std::vector<hardware::DriveCommand> cmd = hold;
  std::size_t elbow = joints.size();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (robot.joint_robot_ids.at(joints[j]) == 52) elbow = j;
  }
  ASSERT_LT(elbow, joints.size());
  cmd[elbow].position = start.position[elbow] + 0.3;
  hardware::HardwareState before_last;
  for (int i = 0; i < 1500; ++i) {
    for (std::size_t j = 0; j < joints.size(); ++j) {
      codec.encode(cmd[j], true, std::span<uint8_t>(image.outputs).subspan(board[j]->output_offset, board[j]->output_bytes));
    }
    if (i == 1499) ringed.read(before_last);
    ASSERT_EQ(master.cycle(image).wkc, image.expected_wkc) << "cycle " << i;
    direct.write(cmd);
    direct.step(0.001);
  }
  hardware::HardwareState a;
  hardware::HardwareState b;
  direct.read(a);
  ringed.read(b);
  // The elbow went most of the way (the drive's own position gains hold it short of the target
  // under the arm's weight, as they do on the sim backend).
  EXPECT_GT(a.position[elbow] - start.position[elbow], 0.15);
  for (std::size_t j = 0; j < joints.size(); ++j) {
    // The references crossed the wire as float32: the two robots agree to far below a drive's
    // encoder resolution.
    EXPECT_NEAR(a.position[j], b.position[j], 1e-5) << joints[j];
  }
  // What the master read in the last cycle is the robot's state before that cycle's step.
  const DriveFeedback f = codec.decode_feedback(
      std::span<const uint8_t>(image.inputs).subspan(board[elbow]->input_offset, board[elbow]->input_bytes));
  EXPECT_EQ(f.status_word, kStatusOperationEnabled);
  EXPECT_NEAR(f.link_position, before_last.position[elbow], 1e-6);
  EXPECT_NEAR(f.torque, before_last.effort[elbow], 1e-3 * std::max(1.0, std::abs(before_last.effort[elbow])));
}

}  // namespace
}  // namespace concert::ethercat

namespace concert::ethercat {
namespace {

TEST(EthercatHardware, DrivesTheRobotBehindTheRingByRobotId) {
  const sim::AssemblyBuilder builder({test_data::kProjectDb});
  const sim::SimulatedRobot robot = builder.build(kAssembly);
  sim::SimHardware ringed(robot, world::World{}, quiet());
  const ProcessDataCatalog pd = ProcessDataCatalog::load(kProcessData);
  VirtualRing ring(simbus::load_assembly(kAssembly), topology::EscCatalog::load(test_data::kProjectDb), RingParams{}, &pd);
  RobotOnRing app(ringed, robot, *pd.find(21));
  ring.set_application([&app](std::span<BoardIo> boards, uint64_t now) { app.exchange(boards, now); });
  uint64_t now = 0;
  LoopbackLink link([&](std::span<const uint8_t> f) { return ring.process(f, now += 1'000'000); });
  EthercatHardware hw(link, pd, MasterParams{.frame_timeout = std::chrono::microseconds(1000),
                                             .state_poll_interval = std::chrono::microseconds(0)});
  EXPECT_EQ(hw.scan().scan(), simbus::simulate_scan(simbus::load_assembly(kAssembly),
                                                     topology::EscCatalog::load(test_data::kProjectDb)));
  // The robot's joints in reverse order: the hardware order is the caller's.
  std::vector<std::pair<std::string, int32_t>> joints;
  for (auto it = ringed.joint_names().rbegin(); it != ringed.joint_names().rend(); ++it) {
    joints.emplace_back(*it, robot.joint_robot_ids.at(*it));
  }
  hw.bind_joints(joints);
  EXPECT_EQ(hw.generation(), 1u);
  ASSERT_EQ(hw.joint_names().size(), joints.size());
  hardware::HardwareState s;
  hw.step(0.001);  // one exchange so the inputs are the robot's
  hw.step(0.001);
  hw.read(s);
  std::size_t elbow = joints.size();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (joints[j].second == 52) elbow = j;
  }
  ASSERT_LT(elbow, joints.size());
  const double from = s.position[elbow];
  std::vector<hardware::DriveCommand> cmd(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) {
    cmd[j].mode = hardware::DriveMode::kPosition;
    cmd[j].position = s.position[j];
  }
  cmd[elbow].position = from + 0.3;
  for (int i = 0; i < 1500; ++i) {
    hw.write(cmd);
    hw.step(0.001);
  }
  hw.read(s);
  EXPECT_GT(s.position[elbow] - from, 0.15);
  EXPECT_EQ(hw.cycle_faults(), 0u);
  EXPECT_NEAR(s.time, 1.502, 1e-9);

  // Mismatches are refused by name, and nothing changes.
  const auto error_of = [&hw](std::vector<std::pair<std::string, int32_t>> j) {
    try {
      hw.bind_joints(j);
    } catch (const hardware::HardwareError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of({{"J_x", 99}}).find("joint 'J_x': no board with robot_id 99 on the ring (robot_ids there: 100, 101, 11"),
            std::string::npos);
  EXPECT_NE(error_of({{"J_base", 100}}).find("joint 'J_base': robot_id 100 is slave 1 (ESC type 50), which is no drive"),
            std::string::npos)
      << error_of({{"J_base", 100}});
  EXPECT_EQ(error_of({{"a", 52}, {"b", 52}}), "joint 'b': robot_id 52 is slave 12, already bound to another joint");
  EXPECT_EQ(hw.generation(), 1u);
  EXPECT_EQ(hw.joint_names().size(), joints.size());

  // A cable pulled: the cycles that miss boards are counted, and the master says where.
  ring.pull_cable("elbow_2");
  hw.write(cmd);
  hw.step(0.001);
  EXPECT_EQ(hw.cycle_faults(), 1u);
  EXPECT_NE(hw.diagnose().text().find("lost the link on port 1"), std::string::npos) << hw.diagnose().text();
}

}  // namespace
}  // namespace concert::ethercat
