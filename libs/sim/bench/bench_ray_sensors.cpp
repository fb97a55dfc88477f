// bench_ray_sensors: the simulated sensors' cost per reading, in a room of 4 walls and 6 boxes and
// cylinders around the drill robot on the mobile platform (services/robot fixtures; the robot's
// geoms are in the scene, in kRobotGeomGroup), sensors at the real platform's mounts
// (concert_resources/sensors/mobile_platform_sensors.yaml).
//   bench_ray_sensors [Google Benchmark flags]
#include <benchmark/benchmark.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <memory>
#include <sstream>

#include "concert/cli/benchmark_main.hpp"
#include "concert/sim/imu_simulator.hpp"
#include "concert/sim/ray_sensors.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "mujoco_scene.hpp"

namespace {

using concert::sim::test::MujocoScene;
namespace sim = concert::sim;

Eigen::Isometry3d pose(const YAML::Node& xyz, const YAML::Node& rpy) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(xyz[0].as<double>(), xyz[1].as<double>(), xyz[2].as<double>());
  t.linear() = (Eigen::AngleAxisd(rpy[2].as<double>(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy[1].as<double>(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy[0].as<double>(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

sim::World room() {
  sim::World w;
  auto shape = [](const std::string& name, concert::world::WorldShape::Type type,
                  Eigen::Vector3d size, Eigen::Vector3d position, double yaw) {
    concert::world::WorldShape s;
    s.name = name;
    s.type = type;
    s.size = size;
    s.position = position;
    s.yaw = yaw;
    return s;
  };
  using Type = concert::world::WorldShape::Type;
  w.walls.push_back(shape("north", Type::kBox, {16, 0.2, 3}, {0, 6, 1.5}, 0));
  w.walls.push_back(shape("south", Type::kBox, {16, 0.2, 3}, {0, -6, 1.5}, 0));
  w.walls.push_back(shape("east", Type::kBox, {0.2, 12, 3}, {8, 0, 1.5}, 0));
  w.walls.push_back(shape("west", Type::kBox, {0.2, 12, 3}, {-8, 0, 1.5}, 0));
  w.obstacles.push_back(shape("crate_a", Type::kBox, {1, 0.8, 1}, {3, 2, 0.5}, 0.3));
  w.obstacles.push_back(shape("crate_b", Type::kBox, {0.6, 0.6, 1.2}, {-2.5, 3, 0.6}, -0.2));
  w.obstacles.push_back(shape("crate_c", Type::kBox, {2, 0.5, 0.8}, {-4, -3, 0.4}, 0.8));
  w.obstacles.push_back(shape("pillar_a", Type::kCylinder, {0.3, 0, 3}, {5, -2, 1.5}, 0));
  w.obstacles.push_back(shape("pillar_b", Type::kCylinder, {0.3, 0, 3}, {-5, 1, 1.5}, 0));
  w.obstacles.push_back(shape("drum", Type::kCylinder, {0.4, 0, 0.9}, {1.5, -3.5, 0.45}, 0));
  return w;
}

struct Setup {
  Setup() {
    std::ifstream in(std::string(ROBOT_FIXTURES) + "/mobile_drill.urdf");
    std::stringstream urdf;
    urdf << in.rdbuf();
    scene = std::make_unique<MujocoScene>(sim::urdf_to_mjcf(urdf.str(), room(), {}));
    const int base = mj_name2id(scene->m(), mjOBJ_BODY, "mobile_base");
    world_T_base.translation() = Eigen::Map<const Eigen::Vector3d>(scene->d()->xpos + 3 * base);
    world_T_base.linear() =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(scene->d()->xmat + 9 * base);
    const YAML::Node yaml =
        YAML::LoadFile(std::string(CONCERT_SHARED_DATA) +
                       "/concert_resources/sensors/mobile_platform_sensors.yaml");
    for (const auto& s : yaml["sensors"]) {
      Eigen::Isometry3d mount = pose(s["xyz"], s["rpy"]);
      if (s["then_rpy"]) {
        mount = mount * pose(YAML::Load("[0, 0, 0]"), s["then_rpy"]);
      }
      const auto type = s["type"].as<std::string>();
      if (type == "lidar3d") {
        lidars.push_back(world_T_base * mount);
      } else if (type == "sonar") {
        sonars.push_back(world_T_base * mount);
      }
    }
  }
  std::unique_ptr<MujocoScene> scene;
  Eigen::Isometry3d world_T_base{Eigen::Isometry3d::Identity()};
  std::vector<Eigen::Isometry3d> lidars;
  std::vector<Eigen::Isometry3d> sonars;
};

Setup& setup() {
  static Setup s;
  return s;
}

void BM_LidarScan(benchmark::State& state) {
  Setup& s = setup();
  const sim::LidarSimulator lidar(sim::LidarParams{});
  std::mt19937_64 rng(1);
  concert::hardware::LidarScan scan;
  for (auto _ : state) {
    lidar.scan(s.scene->m(), s.scene->d(), s.lidars.at(0), rng, scan);
    benchmark::DoNotOptimize(scan.ranges.data());
  }
  state.counters["rays"] = static_cast<double>(scan.ranges.size());
  state.counters["geoms"] = s.scene->m()->ngeom;
}
BENCHMARK(BM_LidarScan)->Unit(benchmark::kMillisecond);

void BM_LidarScanMjRayPerRay(benchmark::State& state) {
  Setup& s = setup();
  const sim::LidarSimulator lidar(sim::LidarParams{});
  concert::hardware::LidarScan scan;
  for (auto _ : state) {
    lidar.scan_reference(s.scene->m(), s.scene->d(), s.lidars.at(0), scan);
    benchmark::DoNotOptimize(scan.ranges.data());
  }
}
BENCHMARK(BM_LidarScanMjRayPerRay)->Unit(benchmark::kMillisecond);

void BM_SonarSet(benchmark::State& state) {
  Setup& s = setup();
  const sim::SonarSimulator sonar(sim::SonarParams{});
  std::mt19937_64 rng(1);
  float sum = 0.0f;
  for (auto _ : state) {
    for (const auto& p : s.sonars) {
      sum += sonar.range(s.scene->m(), s.scene->d(), p, rng);
    }
    benchmark::DoNotOptimize(sum);
  }
  state.counters["sonars"] = static_cast<double>(s.sonars.size());
}
BENCHMARK(BM_SonarSet)->Unit(benchmark::kMicrosecond);

void BM_Scan2dFromTwoLidars(benchmark::State& state) {
  Setup& s = setup();
  const sim::LidarSimulator lidar(sim::LidarParams{});
  std::mt19937_64 rng(1);
  concert::hardware::LidarScan front;
  concert::hardware::LidarScan back;
  lidar.scan(s.scene->m(), s.scene->d(), s.lidars.at(0), rng, front);
  lidar.scan(s.scene->m(), s.scene->d(), s.lidars.at(1), rng, back);
  const std::vector<sim::PosedLidarScan> scans{{&front, s.lidars.at(0)}, {&back, s.lidars.at(1)}};
  concert::hardware::LaserScan2d out;
  for (auto _ : state) {
    sim::derive_scan2d(sim::Scan2dParams{}, scans, s.world_T_base, 0.0, "mobile_base", out);
    benchmark::DoNotOptimize(out.ranges.data());
  }
}
BENCHMARK(BM_Scan2dFromTwoLidars)->Unit(benchmark::kMicrosecond);

void BM_ImuSample(benchmark::State& state) {
  sim::ImuSimulator imu(sim::ImuParams{}, 1);
  concert::hardware::ImuSample sample;
  const Eigen::Vector3d w(0.1, 0.2, 0.3);
  const Eigen::Vector3d f(0.0, 0.0, 9.81);
  for (auto _ : state) {
    imu.sample(w, f, 0.005, sample);
    benchmark::DoNotOptimize(sample.angular_velocity.data());
  }
}
BENCHMARK(BM_ImuSample);

}  // namespace

int main(int argc, char** argv) {
  return concert::cli::benchmark_main("bench_ray_sensors",
                                      "The simulated sensors' cost per reading (VLP-16, sonars, 2D "
                                      "scan, IMU) in a room around the drill robot.",
                                      argc, argv);
}
