// The simulation with every sensor on, at the default rates: does it keep real time on this
// machine, and does each sensor deliver its rate? (issue 15: real-time factor >= 1.0 on 2 cores)
//
// The demo drill robot (deploy/demo/drill_robot.yaml: 14 sensors, 3 RGB-D cameras, 2 VLP-16,
// 8 sonars, 1 IMU) stands on its wheels in the marks world (libs/world/test/fixtures). Two runs:
//   paced:  the 1 kHz loop as the robot service runs it (sleep to each deadline): the real-time
//           factor it holds and the rate each sensor delivers, in simulated time;
//   free:   physics as fast as it goes while the sensor threads work: the headroom.
// Usage: bench_sim_sensors [SECONDS]   (default 10 simulated seconds per run)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "concert/cli/cli.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/world/world.hpp"

namespace {

using namespace concert;
using Clock = std::chrono::steady_clock;

class Counter : public hardware::SensorSink {
 public:
  void on_rgbd(const hardware::RgbdFrame& f) override { count("rgbd", f.sensor); }
  void on_lidar(const hardware::LidarScan& s) override { count("lidar", s.sensor); }
  void on_scan2d(const hardware::LaserScan2d&) override { count("scan2d", "(all lidars)"); }
  void on_sonars(const hardware::SonarRanges&) override { count("sonar", "(all 8)"); }
  void on_imu(const hardware::ImuSample& s) override { count("imu", s.sensor); }
  std::map<std::string, int> take() {
    std::lock_guard lock(mutex_);
    auto out = counts_;
    counts_.clear();
    return out;
  }

 private:
  void count(const char* kind, const std::string& name) {
    std::lock_guard lock(mutex_);
    ++counts_[std::string(kind) + " " + name];
  }
  std::mutex mutex_;
  std::map<std::string, int> counts_;
};

void run(const char* name, sim::SimHardware& sim, Counter& counter, double seconds, bool paced) {
  counter.take();
  const double t0 = sim.time();
  const auto w0 = Clock::now();
  auto deadline = w0;
  int late = 0;
  const int steps = static_cast<int>(seconds * 1000.0);
  for (int i = 0; i < steps; ++i) {
    sim.switch_prepared();
    sim.step(0.001);
    if (paced) {
      deadline += std::chrono::microseconds(1000);
      if (Clock::now() > deadline + std::chrono::microseconds(1000)) {
        ++late;
      }
      std::this_thread::sleep_until(deadline);
    }
  }
  const double wall = std::chrono::duration<double>(Clock::now() - w0).count();
  const double simulated = sim.time() - t0;
  std::printf("%s: %.1f s simulated in %.2f s: real-time factor %.2f%s\n", name, simulated, wall, simulated / wall,
              paced ? "" : " (physics unpaced, sensors in parallel)");
  if (paced) {
    std::printf("  cycles more than 1 ms behind their deadline: %d of %d\n", late, steps);
  }
  for (const auto& [sensor, n] : counter.take()) {
    std::printf("  %-28s %6.1f Hz (simulated time)\n", sensor.c_str(), n / simulated);
  }
}

int bench(double seconds) {
  const std::string source = CONCERT_SOURCE_DIR;
  const sim::AssemblyBuilder builder({source + "/data/module_db"});
  const sim::SimulatedRobot robot = builder.build(source + "/deploy/demo/drill_robot.yaml");
  const world::World world = world::load_world_file(source + "/libs/world/test/fixtures/marks_world.yaml");
  sim::SimParams params;
  params.base_position = {-0.5, 0.0, 0.0};
  sim::SimHardware sim(robot, world, params);
  Counter counter;
  sim.set_sensor_sink(&counter);
  std::printf("bench_sim_sensors: %zu sensors at default rates (camera %.0f Hz %ux%u, lidar %.0f Hz, sonar %.0f Hz, "
              "IMU %.0f Hz), %u hardware threads\n",
              robot.sensors.size(), params.sensors.camera.rate, params.sensors.camera.width,
              params.sensors.camera.height, params.sensors.lidar.rate, params.sensors.sonar.rate,
              params.sensors.imu.rate, std::thread::hardware_concurrency());
  for (int i = 0; i < 500; ++i) {  // settle on the wheels
    sim.step(0.001);
  }
  run("paced 1 kHz loop", sim, counter, seconds, true);
  run("free-running physics", sim, counter, seconds, false);
  sim.set_sensor_sink(nullptr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli(
      "bench_sim_sensors",
      "The simulation with every sensor of the demo drill robot on: the real-time "
      "factor of the paced 1 kHz loop and each sensor's rate, then physics unpaced.",
      std::cout, std::cerr);
  double seconds = 10.0;
  cli.app()
      .add_option("SECONDS", seconds, "simulated seconds per run")
      ->capture_default_str()
      ->check(concert::cli::positive_seconds());
  cli.on_run(cli.app(), [&seconds] { return bench(seconds); });
  return cli.run(argc, argv);
}
