#pragma once
// Seeded random robots of the project's module database (data/module_db): morphologies nobody
// tuned for, for the tests that every service must take any of them (hot swaps between them,
// a drilling approach on each).

#include <random>
#include <string>
#include <vector>

#include "concert/simbus/assembly.hpp"

namespace concert::simbus {

/// Shape of a random robot.
struct RandomRobotParams {
  int min_joints = 3;               ///< arm joints, at least
  int max_joints = 7;               ///< ... and at most
  double riser_probability = 0.3;   ///< a 0.6 m base link under the arm
  double link_probability = 0.5;    ///< a link (straight or bent) after each joint but the last
  /// The joints nearer the base are the larger (A) size: joint i of n is A with probability
  /// 1 - i / n (the shoulder almost always, the wrist seldom).
  bool larger_near_base = true;
};

/// The project database's keys the generator draws from.
const std::vector<std::string>& random_robot_joints();  ///< straight and elbow, A and B
const std::vector<std::string>& random_robot_links();   ///< 300, 400 mm, 45 and 90 deg bends
const std::vector<std::string>& random_robot_tools();   ///< every tool with an ESC

/// A random robot: the Mobile Base Hub on its four steering + wheel legs (as the demo's), an
/// optional riser, an arm of min..max joints with links between, and a tool. Every module with
/// an ESC has a distinct robot_id. Deterministic for a given generator state.
Assembly random_robot(std::mt19937& rng, const RandomRobotParams& params = {});

}  // namespace concert::simbus
