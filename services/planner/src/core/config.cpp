#include "planner/config.hpp"

#include "concert/common/text.hpp"

namespace concert::planner {
namespace {

std::string read_file(const std::filesystem::path& file, const char* what) {
  try {
    return concert::read_file(file, what);
  } catch (const std::runtime_error& e) {
    throw PlannerError(e.what());
  }
}

}  // namespace

Params read_params(config::Document& doc) {
  Params p;
  config::Map root = doc.root();
  // Every key of Params (config/planner.yaml lists them with their defaults and units).
  const std::pair<const char*, double*> non_negative[] = {
      {"camera_distance", &p.camera_distance},
      {"contact_force", &p.contact_force},
      {"torque_margin", &p.torque_margin},
      {"posture_limit_margin", &p.posture_limit_margin},
      {"environment_padding", &p.environment_padding},
      {"drill_bit_radius", &p.drill_bit_radius},
      {"start_tolerance", &p.start_tolerance},
      {"start_joint_tolerance", &p.start_joint_tolerance},
      {"floor_clearance", &p.floor_clearance},
      {"base_range", &p.base_range},
      {"path_attempt_time", &p.path_attempt_time},
      {"nspg_time", &p.nspg_time},
      {"warm_up_time", &p.warm_up_time},
      {"warm_up_path_time", &p.warm_up_path_time},
      {"nspg_tolerance", &p.nspg_tolerance},
      {"nspg_distance_weight", &p.nspg_distance_weight},
      {"nspg_singularity_weight", &p.nspg_singularity_weight},
      {"velocity_scale", &p.velocity_scale},
      {"joint_acceleration", &p.joint_acceleration},
      {"base_linear_velocity", &p.base_linear_velocity},
      {"base_linear_acceleration", &p.base_linear_acceleration},
      {"base_angular_velocity", &p.base_angular_velocity},
      {"base_angular_acceleration", &p.base_angular_acceleration},
      {"sample_period", &p.sample_period},
      {"sensor_map_period", &p.sensor_map_period},
      {"sensor_self_padding", &p.sensor_self_padding},
      {"sensor_floor_band", &p.sensor_floor_band},
      {"sensor_max_speed", &p.sensor_max_speed},
  };
  const std::pair<const char*, double*> positive[] = {
      {"octomap_resolution", &p.octomap_resolution},
      {"planning_time", &p.planning_time},
      {"check_resolution", &p.check_resolution},
      {"sensor_max_range", &p.sensor_max_range},
  };
  const std::pair<const char*, int*> counts[] = {
      {"simplify_iterations", &p.simplify_iterations},
      {"sample_iterations", &p.sample_iterations},
      {"nspg_seeds", &p.nspg_seeds},
      {"nspg_screen", &p.nspg_screen},
      {"nspg_iterations", &p.nspg_iterations},
      {"nspg_enough", &p.nspg_enough},
      {"nspg_memory", &p.nspg_memory},
  };
  for (const auto& [key, value] : non_negative)
    root.number(key, *value, config::Range::non_negative());
  for (const auto& [key, value] : positive) root.number(key, *value, config::Range::positive());
  for (const auto& [key, value] : counts) root.integer(key, *value, 0);
  root.number("drive_torque_fraction", p.drive_torque_fraction, config::Range::between(0.0, 1.0));
  root.number("max_drive_stretch", p.max_drive_stretch, config::Range::at_least(1.0));
  root.integer("memory_models", p.memory_models, 1);
  root.integer("sensor_depth_stride", p.sensor_depth_stride, 1);
  root.integer("sensor_depth_frames", p.sensor_depth_frames, 1);
  root.number("sensor_depth_min_valid", p.sensor_depth_min_valid, config::Range{0.0, 1.0, true});
  root.choice("environment_source", p.environment_source, {"world", "sensors", "both"});
  root.number("floor_height", p.floor_height);
  root.number_or_auto("base_height", p.base_height);
  root.integer("seed", p.seed);
  doc.finish();
  return p;
}

Params parse_params(const std::string& yaml, const std::string& source) {
  try {
    return config::Document::parse(yaml, source).read_with(read_params);
  } catch (const config::ConfigError& e) {
    throw PlannerError(e.what());
  }
}

Params load_params(const std::filesystem::path& file) {
  return parse_params(read_file(file, "params"), file.string());
}

}  // namespace concert::planner
