#pragma once

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>

#include "robot/robot_core.hpp"
#include "concert/sim/sim_hardware.hpp"

namespace concert::robot {

using sim::SimHardware;
using sim::SimParams;
using world::World;
using world::WorldShape;

}  // namespace concert::robot

namespace concert::robot::test {

inline std::string fixture_path(const std::string& name) { return std::string(ROBOT_FIXTURES) + "/" + name; }

inline std::string read_fixture(const std::string& name) {
  std::ifstream in(fixture_path(name));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `cycles` control cycles of `core` (simulated time, as fast as possible).
inline void run_cycles(RobotCore& core, int cycles) {
  for (int i = 0; i < cycles; ++i) {
    core.cycle();
  }
}

/// Runs `cycles` control cycles of `core` sending the base `command` every 100 cycles (the core
/// stops the base after 0.5 s without a command).
inline void drive_base(RobotCore& core, const BaseCommand& command, int cycles) {
  for (int k = 0; k < cycles; ++k) {
    if (k % 100 == 0) {
      core.command_base(command);
    }
    core.cycle();
  }
}

/// The simulated fixed-base drilling arm (fixture arm_drill.urdf) started at `initial_positions`
/// (joint -> [rad]), with its RobotCore at model version 1 after `settle_cycles` cycles.
struct SimulatedArm {
  SimulatedArm(std::map<std::string, double> initial_positions, int settle_cycles)
      : sim(read_fixture("arm_drill.urdf"), World{}, with_initial(std::move(initial_positions))),
        core(sim) {
    core.set_model(read_fixture("arm_drill.urdf"), 1);
    run_cycles(core, settle_cycles);
  }

  SimHardware sim;
  RobotCore core;

 private:
  static SimParams with_initial(std::map<std::string, double> positions) {
    SimParams params;
    params.initial_positions = std::move(positions);
    return params;
  }
};

inline std::size_t hw_index(const RobotState& s, const std::string& joint) {
  for (std::size_t i = 0; i < s.joint_names.size(); ++i) {
    if (s.joint_names[i] == joint) {
      return i;
    }
  }
  return s.joint_names.size();
}

}  // namespace concert::robot::test
