// Reads the nav service's parameter file (config/nav.yaml lists every key with its default).
#include "concert/config/config.hpp"
#include "nav/navigator.hpp"

namespace concert::nav {
namespace {

using config::Range;

NavParams read_params(config::Document& doc) {
  NavParams p;
  config::Map root = doc.root();
  root.number("control_rate", p.control_rate, Range::positive());
  root.number("cruise_speed", p.cruise_speed, Range::positive());
  root.number("max_acceleration", p.max_acceleration, Range::positive());
  root.number("max_angular_acceleration", p.max_angular_acceleration, Range::positive());
  root.number("drive_torque_fraction", p.drive_torque_fraction, Range{0.0, 1.0, true});
  root.number("arm_home_tolerance", p.arm_home_tolerance, Range::non_negative());
  root.integer("max_replans", p.max_replans, 0, 1000);
  root.number("initial_std_xy", p.initial_std_xy, Range::positive());
  root.number("initial_std_yaw", p.initial_std_yaw, Range::positive());
  root.number("wall_standoff", p.wall_standoff, Range::non_negative());
  root.number("wall_clearance", p.wall_clearance, Range::non_negative());

  config::Map vehicle = root.section("vehicle");
  vehicle.number("max_linear_speed", p.vehicle.max_linear_speed, Range::positive());
  vehicle.number("max_angular_speed", p.vehicle.max_angular_speed, Range::positive());

  config::Map costmap = root.section("costmap");
  costmap.boolean("unknown_is_lethal", p.costmap.unknown_is_lethal);
  costmap.number("inflation_radius", p.costmap.inflation_radius, Range::positive());
  costmap.number("cost_scaling_factor", p.costmap.cost_scaling_factor, Range::positive());
  costmap.number("obstacle_max_range", p.costmap.obstacle_max_range, Range::positive());
  costmap.number("raytrace_max_range", p.costmap.raytrace_max_range, Range::positive());

  config::Map planner = root.section("planner");
  planner.number("cost_penalty", p.planner.cost_penalty, Range::non_negative());
  planner.number("max_planning_time", p.planner.max_planning_time, Range::positive());
  planner.boolean("smooth", p.planner.smooth);
  planner.number("escape_distance", p.planner.escape_distance, Range::non_negative());

  config::Map controller = root.section("controller");
  controller.number("lookahead_time", p.controller.lookahead_time, Range::positive());
  controller.number("min_lookahead", p.controller.min_lookahead, Range::positive());
  controller.number("max_lookahead", p.controller.max_lookahead, Range::positive());
  controller.number("xy_goal_tolerance", p.controller.xy_goal_tolerance, Range::positive());
  controller.number("yaw_goal_tolerance", p.controller.yaw_goal_tolerance, Range::positive());
  controller.number("approach_distance", p.controller.approach_distance, Range::non_negative());
  controller.number("min_approach_speed", p.controller.min_approach_speed, Range::positive());
  controller.number("escape_speed", p.controller.escape_speed, Range::positive());
  controller.number("heading_gain", p.controller.heading_gain, Range::positive());
  controller.number("stop_margin", p.controller.stop_margin, Range::non_negative());
  controller.number("blocked_timeout", p.controller.blocked_timeout, Range::positive());
  controller.number("max_path_deviation", p.controller.max_path_deviation, Range::positive());

  config::Map localiser = root.section("localiser");
  localiser.integer("particles", p.localiser.particles, 10, 1000000);
  localiser.integer("recovery_particles", p.localiser.recovery_particles, 10, 10000000);
  localiser.integer("max_beams", p.localiser.max_beams, 1, 100000);
  localiser.number("sigma_hit", p.localiser.sigma_hit, Range::positive());
  localiser.boolean("refine", p.localiser.refine);
  localiser.number("lost_match_ratio", p.localiser.lost_match_ratio, Range::between(0.0, 1.0));
  localiser.integer("lost_after", p.localiser.lost_after, 1, 100000);

  doc.finish();
  return p;
}

}  // namespace

NavParams load_params(const std::string& path) {
  try {
    return config::Document::load(path).read_with(read_params);
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(e.what());
  }
}

}  // namespace concert::nav
