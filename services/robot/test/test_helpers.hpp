#pragma once

#include <fstream>
#include <sstream>
#include <string>

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

inline std::size_t hw_index(const RobotState& s, const std::string& joint) {
  for (std::size_t i = 0; i < s.joint_names.size(); ++i) {
    if (s.joint_names[i] == joint) {
      return i;
    }
  }
  return s.joint_names.size();
}

}  // namespace concert::robot::test
