#pragma once
// The service's parameters from one YAML file (sections robot, sim, loop, node); see README.

#include <string>

#include "concert/config/config.hpp"
#include "robot/loop.hpp"
#include "robot/robot_core.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "robot_node.hpp"

namespace concert::robot::dds {

struct ServiceParams {
  RobotParams robot;
  sim::SimParams sim;
  LoopParams loop;
  NodeParams node;
};

/// Parses parameters YAML; unknown sections/keys and wrong types are errors naming `source`,
/// the key and the line (config::ConfigError, a std::runtime_error). Missing keys keep their
/// defaults.
ServiceParams parse_service_params(const std::string& yaml_text, const std::string& source);
ServiceParams load_service_params(const std::string& path);
/// Reads the parameters of `doc`, starting from the defaults.
ServiceParams read_service_params(config::Document& doc);

}  // namespace concert::robot::dds
