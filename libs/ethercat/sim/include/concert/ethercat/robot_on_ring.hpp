#pragma once
// The simulated robot behind the virtual ring's drive boards: the boards' outputs become the
// MuJoCo robot's drive commands (libs/sim, the same physics as the robot service's sim backend),
// one physics period per process data frame, and its joints' state becomes the boards' inputs.
// A board is found by its module's robot_id, as the real drives are told apart.

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/ethercat/drive_pdo.hpp"
#include "concert/ethercat/virtual_ring.hpp"
#include "concert/hardware/hardware.hpp"
#include "concert/sim/sim_assembly.hpp"

namespace concert::ethercat {

struct RobotOnRingParams {
  double period = 0.001;              ///< simulated seconds per process data frame
  double temperature = 25.0;          ///< what the boards report as motor and board temperature
};

class RobotOnRing {
 public:
  /// `hardware`: the simulated robot built from `robot` (its joints in hardware order);
  /// `drive_board`: the process data of the drive boards. Throws std::runtime_error naming a
  /// joint whose module has no robot_id.
  RobotOnRing(hardware::Hardware& hardware, const sim::SimulatedRobot& robot,
              const BoardProcessData& drive_board, RobotOnRingParams params = {});

  /// The ring's application: every drive board's outputs in, one physics period, its joint's
  /// state out. A joint whose board is not in OP (or not told to run) holds where it is, as a
  /// drive with its brake closed. Boards of robot_ids no joint has are left alone.
  void exchange(std::span<BoardIo> boards, uint64_t now_ns);

  /// Joints that found no board in the last frame (their robot_id is not on the ring or the
  /// board is not in OP): for logs and tests.
  const std::vector<std::string>& unmatched() const { return unmatched_; }
  uint64_t steps() const { return steps_; }

 private:
  hardware::Hardware& hardware_;
  DriveCodec codec_;
  int32_t drive_type_ = 0;
  RobotOnRingParams params_;
  std::vector<int32_t> robot_ids_;          // per hardware joint
  std::vector<hardware::DriveCommand> commands_;
  std::vector<bool> holding_;               // per joint: held at hold_at_
  std::vector<double> hold_at_;
  hardware::HardwareState state_;
  std::vector<int> board_of_;               // per joint: index into the frame's boards, -1
  std::vector<std::string> unmatched_;
  uint64_t steps_ = 0;
};

/// The assembly's MuJoCo robot behind a ring's drive boards, owning what it needs.
class RobotBehindRing {
 public:
  /// Builds the robot of `assembly_file` from `module_dbs` (as the sim backend does; no
  /// sensors), in `world_file` (empty: an empty world), and sets it as `ring`'s application.
  /// Throws std::runtime_error naming what is wrong (no drive board in `process_data`, a
  /// joint without robot_id, a module the databases lack).
  RobotBehindRing(VirtualRing& ring, const std::vector<std::string>& module_dbs,
                  const std::string& assembly_file, const std::string& world_file,
                  const ProcessDataCatalog& process_data);
  ~RobotBehindRing();
  std::size_t joints() const;
  const RobotOnRing& robot() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::ethercat
