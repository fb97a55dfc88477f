#include "concert/simbus/random_robot.hpp"

#include <stdexcept>

namespace concert::simbus {

const std::vector<std::string>& random_robot_joints() {
  static const std::vector<std::string> keys{"concert_straight_a", "concert_elbow_a", "concert_straight_b",
                                             "concert_elbow_b"};
  return keys;
}

const std::vector<std::string>& random_robot_links() {
  static const std::vector<std::string> keys{"concert_link_300", "concert_link_400", "concert_link_elbow_45",
                                             "concert_link_elbow_90"};
  return keys;
}

const std::vector<std::string>& random_robot_tools() {
  // The passive grippers carry no ESC: the bus cannot see them, so no scan can name them.
  static const std::vector<std::string> keys{"concert_drill", "concert_spraying_tool", "concert_sanding_tool",
                                             "concert_active_gripper_panel", "concert_active_gripper_tube"};
  return keys;
}

Assembly random_robot(std::mt19937& rng, const RandomRobotParams& params) {
  if (params.min_joints < 1 || params.max_joints < params.min_joints) {
    throw std::invalid_argument("random_robot: need 1 <= min_joints <= max_joints, got " +
                                std::to_string(params.min_joints) + " and " + std::to_string(params.max_joints));
  }
  // Draws by hand from the generator's raw output (not std::uniform_*_distribution, whose
  // algorithms differ between standard libraries): the same seed gives the same robot anywhere.
  const auto below = [&rng](std::size_t n) { return static_cast<std::size_t>(rng() % n); };
  const auto chance = [&rng](double p) { return static_cast<double>(rng()) / 4294967296.0 < p; };

  Assembly a;
  a.source = "<random robot>";
  a.modules = {
      {"base", "concert_mobile_base_hub", "", 0, {100, 101}},
      {"steer_fl", "concert_steering_fl_rr", "base", 1, {11}},
      {"wheel_fl", "concert_wheel", "steer_fl", 1, {12}},
      {"steer_fr", "concert_steering_fr_rl", "base", 2, {21}},
      {"wheel_fr", "concert_wheel", "steer_fr", 1, {22}},
      {"steer_rl", "concert_steering_fr_rl", "base", 3, {31}},
      {"wheel_rl", "concert_wheel", "steer_rl", 1, {32}},
      {"steer_rr", "concert_steering_fl_rr", "base", 4, {41}},
      {"wheel_rr", "concert_wheel", "steer_rr", 1, {42}},
  };
  std::string parent = "base";
  int connector = 5;  // the hub's arm connector
  const auto mount = [&](const std::string& name, const std::string& key, std::vector<int32_t> ids) {
    a.modules.push_back({name, key, parent, connector, std::move(ids)});
    parent = name;
    connector = 1;
  };
  if (chance(params.riser_probability)) mount("riser", "concert_base_link_600", {});
  const int joints =
      params.min_joints + static_cast<int>(below(static_cast<std::size_t>(params.max_joints - params.min_joints + 1)));
  int links = 0;
  for (int i = 0; i < joints; ++i) {
    const bool larger = !params.larger_near_base || chance(1.0 - static_cast<double>(i) / joints);
    const bool elbow = chance(0.5);
    const std::string& key = random_robot_joints()[(elbow ? 1 : 0) + (larger ? 0 : 2)];
    mount("joint_" + std::to_string(i + 1), key, {51 + i});
    if (i + 1 < joints && chance(params.link_probability)) {
      mount("link_" + std::to_string(++links), random_robot_links()[below(random_robot_links().size())], {});
    }
  }
  mount("tool", random_robot_tools()[below(random_robot_tools().size())], {60});
  return a;
}

}  // namespace concert::simbus
