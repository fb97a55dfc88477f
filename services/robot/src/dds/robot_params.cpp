#include "robot_params.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

namespace concert::robot::dds {
namespace {

struct Section {
  const std::string& source;
  std::string name;
  std::map<std::string, std::function<void(const YAML::Node&)>> keys;

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::runtime_error("parameters '" + source + "': " + name + "." + key + ": " + what);
  }
  template <class T> std::function<void(const YAML::Node&)> to(const std::string& key, T& out) {
    return [this, key, &out](const YAML::Node& n) {
      try {
        out = n.as<T>();
      } catch (const YAML::Exception&) {
        fail(key, "wrong type");
      }
    };
  }
  template <class T> void add(const std::string& key, T& out) { keys[key] = to(key, out); }
  void apply(const YAML::Node& node) {
    if (!node) {
      return;
    }
    if (!node.IsMap()) {
      throw std::runtime_error("parameters '" + source + "': " + name + ": expected a map");
    }
    for (const auto& kv : node) {
      const auto key = kv.first.as<std::string>();
      const auto it = keys.find(key);
      if (it == keys.end()) {
        fail(key, "unknown key");
      }
      it->second(kv.second);
    }
  }
};

}  // namespace

ServiceParams parse_service_params(const std::string& yaml_text, const std::string& source) {
  ServiceParams p;
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("parameters '" + source + "': YAML error at line " + std::to_string(e.mark.line + 1) +
                             ": " + e.msg);
  }
  if (root.IsNull()) {
    return p;
  }
  if (!root.IsMap()) {
    throw std::runtime_error("parameters '" + source + "': expected a map with robot, sim, loop, node");
  }
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (key != "robot" && key != "sim" && key != "loop" && key != "node") {
      throw std::runtime_error("parameters '" + source + "': unknown section '" + key +
                               "' (robot, sim, loop, node)");
    }
  }
  Section robot{source, "robot", {}};
  robot.add("period", p.robot.period);
  robot.add("end_effector_frame", p.robot.end_effector_frame);
  robot.add("default_wheel_radius", p.robot.default_wheel_radius);
  robot.add("wrench_filter_time_constant", p.robot.wrench_filter_time_constant);
  robot.add("base_command_timeout", p.robot.base_command_timeout);
  robot.add("velocity_guard_gain", p.robot.velocity_guard_gain);
  robot.add("trajectory_path_tolerance", p.robot.trajectory_path_tolerance);
  robot.add("trajectory_base_path_tolerance", p.robot.trajectory_base_path_tolerance);
  robot.add("trajectory_goal_tolerance", p.robot.trajectory_goal_tolerance);
  robot.add("trajectory_base_goal_tolerance", p.robot.trajectory_base_goal_tolerance);
  robot.add("trajectory_goal_time", p.robot.trajectory_goal_time);
  robot.add("trajectory_base_gain", p.robot.trajectory_base_gain);
  robot.add("trajectory_base_deadband", p.robot.trajectory_base_deadband);
  robot.add("trajectory_steering_rate", p.robot.trajectory_steering_rate);
  robot.apply(root["robot"]);

  Section sim{source, "sim", {}};
  sim.add("timestep", p.sim.timestep);
  sim.add("position_stiffness", p.sim.position_stiffness);
  sim.add("position_damping", p.sim.position_damping);
  sim.add("velocity_gain", p.sim.velocity_gain);
  sim.add("armature", p.sim.armature);
  sim.add("friction_scale", p.sim.friction_scale);
  sim.add("damping_scale", p.sim.damping_scale);
  sim.add("wheel_friction", p.sim.wheel_friction);
  sim.add("robot_friction", p.sim.robot_friction);
  sim.add("base_yaw", p.sim.base_yaw);
  sim.add("initial_positions", p.sim.initial_positions);
  sim.add("position_noise", p.sim.position_noise);
  sim.add("effort_noise", p.sim.effort_noise);
  sim.add("seed", p.sim.seed);
  sim.add("package_paths", p.sim.package_paths);
  sim.keys["floating_base"] = [&](const YAML::Node& n) {
    try {
      p.sim.floating_base = n.as<bool>();
    } catch (const YAML::Exception&) {
      sim.fail("floating_base", "expected true or false");
    }
  };
  sim.keys["base_position"] = [&](const YAML::Node& n) {
    try {
      const auto v = n.as<std::vector<double>>();
      if (v.size() != 3) {
        throw YAML::Exception(YAML::Mark::null_mark(), "size");
      }
      p.sim.base_position = {v[0], v[1], v[2]};
    } catch (const YAML::Exception&) {
      sim.fail("base_position", "expected [x, y, z]");
    }
  };
  sim.apply(root["sim"]);

  Section loop{source, "loop", {}};
  loop.add("real_time", p.loop.real_time);
  loop.add("spin_time", p.loop.spin_time);
  loop.add("fifo_priority", p.loop.fifo_priority);
  loop.apply(root["loop"]);

  Section node{source, "node", {}};
  node.add("service_name", p.node.service_name);
  node.add("odometry_decimation", p.node.odometry_decimation);
  node.add("wrench_decimation", p.node.wrench_decimation);
  node.apply(root["node"]);

  if (p.robot.period <= 0.0 || p.sim.timestep <= 0.0) {
    throw std::runtime_error("parameters '" + source + "': periods and timestep must be positive");
  }
  p.loop.period = p.robot.period;
  return p;
}

ServiceParams load_service_params(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("cannot open parameters file '" + path + "'");
  }
  std::stringstream s;
  s << in.rdbuf();
  return parse_service_params(s.str(), path);
}

}  // namespace concert::robot::dds
