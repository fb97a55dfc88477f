#include "robot_params.hpp"

namespace concert::robot::dds {

using sim::SensorParams;

ServiceParams read_service_params(config::Document& doc) {
  ServiceParams p;
  const auto non_negative = config::Range::non_negative();
  const auto positive = config::Range::positive();
  config::Map root = doc.root();

  config::Map robot = root.section("robot");
  robot.number("period", p.robot.period, positive);
  robot.string("end_effector_frame", p.robot.end_effector_frame);
  robot.number("default_wheel_radius", p.robot.default_wheel_radius, positive);
  robot.number("wrench_filter_time_constant", p.robot.wrench_filter_time_constant, non_negative);
  robot.number("base_command_timeout", p.robot.base_command_timeout, positive);
  robot.number("velocity_guard_gain", p.robot.velocity_guard_gain, non_negative);
  robot.number("trajectory_path_tolerance", p.robot.trajectory_path_tolerance, positive);
  robot.number("trajectory_base_path_tolerance", p.robot.trajectory_base_path_tolerance, positive);
  robot.number("trajectory_goal_tolerance", p.robot.trajectory_goal_tolerance, positive);
  robot.number("trajectory_base_goal_tolerance", p.robot.trajectory_base_goal_tolerance, positive);
  robot.number("trajectory_goal_time", p.robot.trajectory_goal_time, positive);
  robot.number("trajectory_base_gain", p.robot.trajectory_base_gain, non_negative);
  robot.number("trajectory_base_deadband", p.robot.trajectory_base_deadband, non_negative);
  robot.number("trajectory_steering_rate", p.robot.trajectory_steering_rate, positive);
  robot.number("steering_acceleration", p.robot.steering_acceleration, positive);

  config::Map sim = root.section("sim");
  sim.number("timestep", p.sim.timestep, positive);
  sim.number("position_stiffness", p.sim.position_stiffness, non_negative);
  sim.number("position_damping", p.sim.position_damping, non_negative);
  sim.number("velocity_gain", p.sim.velocity_gain, non_negative);
  sim.number("armature", p.sim.armature, non_negative);
  sim.number("friction_scale", p.sim.friction_scale, non_negative);
  sim.number("damping_scale", p.sim.damping_scale, non_negative);
  sim.number("wheel_friction", p.sim.wheel_friction, non_negative);
  sim.number("robot_friction", p.sim.robot_friction, non_negative);
  sim.number("sanding_disc_friction", p.sim.sanding_disc_friction);
  sim.boolean_or_auto("floating_base", p.sim.floating_base);
  std::vector<double> base_position(p.sim.base_position.data(), p.sim.base_position.data() + 3);
  sim.numbers("base_position", base_position, 3);
  p.sim.base_position = {base_position[0], base_position[1], base_position[2]};
  sim.number("base_yaw", p.sim.base_yaw);
  sim.number_map("initial_positions", p.sim.initial_positions);
  sim.number("position_noise", p.sim.position_noise, non_negative);
  sim.number("effort_noise", p.sim.effort_noise, non_negative);
  sim.integer("seed", p.sim.seed);
  sim.string_map("package_paths", p.sim.package_paths);

  // Simulated sensors (libs/sim sensor_params.hpp has each value's source).
  config::Map sensors = root.section("sensors");
  SensorParams& sp = p.sim.sensors;
  sensors.boolean("enabled", sp.enabled);
  sensors.integer("seed", sp.seed);
  config::Map camera = sensors.section("camera");
  camera.number("rate", sp.camera.rate, positive);
  camera.integer("width", sp.camera.width, 16, 4096);
  camera.integer("height", sp.camera.height, 16, 4096);
  camera.number("focal", sp.camera.focal, positive);
  camera.number("depth_min", sp.camera.depth_min, non_negative);
  camera.number("depth_max", sp.camera.depth_max, positive);
  camera.number("depth_subpixel", sp.camera.depth_subpixel, non_negative);
  camera.number("depth_baseline", sp.camera.depth_baseline, positive);
  camera.number("depth_focal", sp.camera.depth_focal, positive);
  camera.number("rgb_noise", sp.camera.rgb_noise, non_negative);
  camera.boolean("noise", sp.camera.noise);
  config::Map lidar = sensors.section("lidar");
  lidar.number("rate", sp.lidar.rate, positive);
  lidar.integer("rings", sp.lidar.rings, 1, 128);
  lidar.number("elevation_min", sp.lidar.elevation_min);
  lidar.number("elevation_max", sp.lidar.elevation_max);
  lidar.integer("columns", sp.lidar.columns, 1, 36000);
  lidar.number("range_min", sp.lidar.range_min, non_negative);
  lidar.number("range_max", sp.lidar.range_max, positive);
  lidar.number("range_noise", sp.lidar.range_noise, non_negative);
  lidar.boolean("noise", sp.lidar.noise);
  config::Map scan2d = sensors.section("scan2d");
  scan2d.integer("bins", sp.scan2d.bins, 1, 36000);
  scan2d.number("height_min", sp.scan2d.height_min);
  scan2d.number("height_max", sp.scan2d.height_max);
  scan2d.number("range_max", sp.scan2d.range_max, positive);
  config::Map sonar = sensors.section("sonar");
  sonar.number("rate", sp.sonar.rate, positive);
  sonar.number("range_min", sp.sonar.range_min, non_negative);
  sonar.number("range_max", sp.sonar.range_max, positive);
  sonar.number("field_of_view", sp.sonar.field_of_view, positive);
  sonar.number("range_noise", sp.sonar.range_noise, non_negative);
  sonar.integer("rays", sp.sonar.rays, 1, 1000);
  sonar.boolean("noise", sp.sonar.noise);
  config::Map imu = sensors.section("imu");
  imu.number("rate", sp.imu.rate, positive);
  imu.number("gyro_noise_density", sp.imu.gyro_noise_density, non_negative);
  imu.number("accel_noise_density", sp.imu.accel_noise_density, non_negative);
  imu.number("gyro_bias_sigma", sp.imu.gyro_bias_sigma, non_negative);
  imu.number("accel_bias_sigma", sp.imu.accel_bias_sigma, non_negative);
  imu.number("gyro_bias_walk", sp.imu.gyro_bias_walk, non_negative);
  imu.number("accel_bias_walk", sp.imu.accel_bias_walk, non_negative);
  imu.boolean("noise", sp.imu.noise);

  config::Map loop = root.section("loop");
  loop.boolean("real_time", p.loop.real_time);
  loop.number("spin_time", p.loop.spin_time, non_negative);
  loop.integer("fifo_priority", p.loop.fifo_priority, 0, 99);

  config::Map node = root.section("node");
  node.string("service_name", p.node.service_name, false);
  node.integer("odometry_decimation", p.node.odometry_decimation, 1);
  node.integer("wrench_decimation", p.node.wrench_decimation, 1);
  node.number("safety_timeout", p.node.safety_timeout, non_negative);

  doc.finish();
  p.loop.period = p.robot.period;
  return p;
}

ServiceParams parse_service_params(const std::string& yaml_text, const std::string& source) {
  return config::Document::parse(yaml_text, source).read_with(read_service_params);
}

ServiceParams load_service_params(const std::string& path) {
  return config::Document::load(path).read_with(read_service_params);
}

}  // namespace concert::robot::dds
