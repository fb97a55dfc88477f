#include "robot_params.hpp"

namespace concert::robot::dds {

using sim::SensorParams;

namespace {

const auto kNonNegative = config::Range::non_negative();
const auto kPositive = config::Range::positive();

void read_robot(config::Map& root, RobotParams& robot_params) {
  config::Map robot = root.section("robot");
  robot.number("period", robot_params.period, kPositive);
  robot.string("end_effector_frame", robot_params.end_effector_frame);
  robot.number("default_wheel_radius", robot_params.default_wheel_radius, kPositive);
  robot.number("wrench_filter_time_constant", robot_params.wrench_filter_time_constant, kNonNegative);
  robot.number("base_command_timeout", robot_params.base_command_timeout, kPositive);
  robot.number("velocity_guard_gain", robot_params.velocity_guard_gain, kNonNegative);
  robot.number("position_guard_margin", robot_params.position_guard_margin, kNonNegative);
  robot.number("position_guard_torque", robot_params.position_guard_torque, kNonNegative);
  robot.number("position_guard_damping", robot_params.position_guard_damping, kNonNegative);
  robot.number("trajectory_path_tolerance", robot_params.trajectory_path_tolerance, kPositive);
  robot.number("trajectory_base_path_tolerance", robot_params.trajectory_base_path_tolerance, kPositive);
  robot.number("trajectory_goal_tolerance", robot_params.trajectory_goal_tolerance, kPositive);
  robot.number("trajectory_base_goal_tolerance", robot_params.trajectory_base_goal_tolerance, kPositive);
  robot.number("trajectory_goal_time", robot_params.trajectory_goal_time, kPositive);
  robot.number("trajectory_base_gain", robot_params.trajectory_base_gain, kNonNegative);
  robot.number("trajectory_base_deadband", robot_params.trajectory_base_deadband, kNonNegative);
  robot.number("trajectory_steering_rate", robot_params.trajectory_steering_rate, kPositive);
  robot.number("steering_acceleration", robot_params.steering_acceleration, kPositive);
}

void read_sim(config::Map& root, sim::SimParams& sim_params) {
  config::Map sim = root.section("sim");
  sim.number("timestep", sim_params.timestep, kPositive);
  sim.number("position_stiffness", sim_params.position_stiffness, kNonNegative);
  sim.number("position_damping", sim_params.position_damping, kNonNegative);
  sim.number("velocity_gain", sim_params.velocity_gain, kNonNegative);
  sim.number("armature", sim_params.armature, kNonNegative);
  sim.number("friction_scale", sim_params.friction_scale, kNonNegative);
  sim.number("damping_scale", sim_params.damping_scale, kNonNegative);
  sim.number("wheel_friction", sim_params.wheel_friction, kNonNegative);
  sim.number("robot_friction", sim_params.robot_friction, kNonNegative);
  sim.number("sanding_disc_friction", sim_params.sanding_disc_friction);
  sim.boolean_or_auto("floating_base", sim_params.floating_base);
  std::vector<double> base_position(sim_params.base_position.data(), sim_params.base_position.data() + 3);
  sim.numbers("base_position", base_position, 3);
  sim_params.base_position = {base_position[0], base_position[1], base_position[2]};
  sim.number("base_yaw", sim_params.base_yaw);
  sim.number_map("initial_positions", sim_params.initial_positions);
  sim.number("position_noise", sim_params.position_noise, kNonNegative);
  sim.number("effort_noise", sim_params.effort_noise, kNonNegative);
  sim.integer("seed", sim_params.seed);
  sim.string_map("package_paths", sim_params.package_paths);
}

/// Simulated sensors (libs/sim sensor_params.hpp has each value's source).
void read_sensors(config::Map& root, SensorParams& sp) {
  config::Map sensors = root.section("sensors");
  sensors.boolean("enabled", sp.enabled);
  sensors.integer("seed", sp.seed);
  config::Map camera = sensors.section("camera");
  camera.number("rate", sp.camera.rate, kPositive);
  camera.integer("width", sp.camera.width, 16, 4096);
  camera.integer("height", sp.camera.height, 16, 4096);
  camera.number("focal", sp.camera.focal, kPositive);
  camera.number("depth_min", sp.camera.depth_min, kNonNegative);
  camera.number("depth_max", sp.camera.depth_max, kPositive);
  camera.number("depth_subpixel", sp.camera.depth_subpixel, kNonNegative);
  camera.number("depth_baseline", sp.camera.depth_baseline, kPositive);
  camera.number("depth_focal", sp.camera.depth_focal, kPositive);
  camera.number("rgb_noise", sp.camera.rgb_noise, kNonNegative);
  camera.boolean("noise", sp.camera.noise);
  config::Map lidar = sensors.section("lidar");
  lidar.number("rate", sp.lidar.rate, kPositive);
  lidar.integer("rings", sp.lidar.rings, 1, 128);
  lidar.number("elevation_min", sp.lidar.elevation_min);
  lidar.number("elevation_max", sp.lidar.elevation_max);
  lidar.integer("columns", sp.lidar.columns, 1, 36000);
  lidar.number("range_min", sp.lidar.range_min, kNonNegative);
  lidar.number("range_max", sp.lidar.range_max, kPositive);
  lidar.number("range_noise", sp.lidar.range_noise, kNonNegative);
  lidar.boolean("noise", sp.lidar.noise);
  config::Map scan2d = sensors.section("scan2d");
  scan2d.integer("bins", sp.scan2d.bins, 1, 36000);
  scan2d.number("height_min", sp.scan2d.height_min);
  scan2d.number("height_max", sp.scan2d.height_max);
  scan2d.number("range_max", sp.scan2d.range_max, kPositive);
  config::Map sonar = sensors.section("sonar");
  sonar.number("rate", sp.sonar.rate, kPositive);
  sonar.number("range_min", sp.sonar.range_min, kNonNegative);
  sonar.number("range_max", sp.sonar.range_max, kPositive);
  sonar.number("field_of_view", sp.sonar.field_of_view, kPositive);
  sonar.number("range_noise", sp.sonar.range_noise, kNonNegative);
  sonar.integer("rays", sp.sonar.rays, 1, 1000);
  sonar.boolean("noise", sp.sonar.noise);
  config::Map imu = sensors.section("imu");
  imu.number("rate", sp.imu.rate, kPositive);
  imu.number("gyro_noise_density", sp.imu.gyro_noise_density, kNonNegative);
  imu.number("accel_noise_density", sp.imu.accel_noise_density, kNonNegative);
  imu.number("gyro_bias_sigma", sp.imu.gyro_bias_sigma, kNonNegative);
  imu.number("accel_bias_sigma", sp.imu.accel_bias_sigma, kNonNegative);
  imu.number("gyro_bias_walk", sp.imu.gyro_bias_walk, kNonNegative);
  imu.number("accel_bias_walk", sp.imu.accel_bias_walk, kNonNegative);
  imu.boolean("noise", sp.imu.noise);
}

void read_loop_and_node(config::Map& root, ServiceParams& p) {
  config::Map loop = root.section("loop");
  loop.boolean("real_time", p.loop.real_time);
  loop.number("spin_time", p.loop.spin_time, kNonNegative);
  loop.integer("fifo_priority", p.loop.fifo_priority, 0, 99);

  config::Map node = root.section("node");
  node.string("service_name", p.node.service_name, false);
  node.integer("odometry_decimation", p.node.odometry_decimation, 1);
  node.integer("wrench_decimation", p.node.wrench_decimation, 1);
  node.number("safety_timeout", p.node.safety_timeout, kNonNegative);
}

}  // namespace

ServiceParams read_service_params(config::Document& doc) {
  ServiceParams p;
  config::Map root = doc.root();
  read_robot(root, p.robot);
  read_sim(root, p.sim);
  read_sensors(root, p.sim.sensors);
  read_loop_and_node(root, p);
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
