// bench_robot: control-loop period jitter in real-time mode and the simulation's real-time
// factor, for the 6-DoF drill arm on the four-legged mobile base (services/robot fixtures).
//   bench_robot [--seconds S] [--urdf FILE]
// Plain main (not Google Benchmark): the quantities are loop statistics, not per-call times.
// Base commands come from another thread (as from DDS in the service); the loop only cycles.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

#include "concert/cli/cli.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "robot/loop.hpp"
#include "robot/robot_core.hpp"

namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("cannot open '" + path + "'");
  }
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Setup {
  explicit Setup(const std::string& urdf) : sim(urdf, concert::world::World{}, {}), core(sim) {
    core.set_model(urdf, 1);
    for (int i = 0; i < 100; ++i) {
      core.cycle();
    }
    // A realistic load: Cartesian impedance on the arm and the base driving.
    concert::robot::CartesianCommand cart;
    cart.model_version = 1;
    cart.target_pose = core.state().end_effector_pose;
    core.command_cartesian(cart);
  }
  ~Setup() {
    stop = true;
    if (commander.joinable()) {
      commander.join();
    }
  }
  /// Base commands every `period` of wall time from another thread, as the DDS threads send
  /// them in the service (the loop thread only cycles).
  void command_from_another_thread(std::chrono::milliseconds period) {
    commander = std::thread([this, period] {
      while (!stop) {
        core.command_base({1, 0.2, 0.0, 0.1});
        std::this_thread::sleep_for(period);
      }
    });
  }
  void tick() { core.cycle(); }
  concert::sim::SimHardware sim;
  concert::robot::RobotCore core;
  std::atomic<bool> stop{false};
  std::thread commander;
};

int bench(double seconds, const std::string& urdf_path) {
  try {
    const std::string urdf = read_file(urdf_path);
    const auto cycles = static_cast<std::uint64_t>(seconds * 1000.0);
    {
      Setup s(urdf);
      s.command_from_another_thread(std::chrono::milliseconds(15));  // ~100 ms of simulated time
      concert::robot::Loop loop({0.001, false, false}, [&] { s.tick(); });
      const auto stats = loop.run(cycles);
      std::printf("as fast as possible: %llu cycles of 1 ms, wall %.3f s, real-time factor %.2f, %.1f us/cycle\n",
                  static_cast<unsigned long long>(stats.cycles), stats.wall_time, seconds / stats.wall_time,
                  1e6 * stats.wall_time / static_cast<double>(stats.cycles));
    }
    {
      // Physics alone (drives holding), to tell simulation cost from controller cost.
      concert::sim::SimHardware sim(urdf, concert::world::World{}, {});
      const auto start = std::chrono::steady_clock::now();
      for (std::uint64_t k = 0; k < cycles; ++k) {
        sim.step(0.001);
      }
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::printf("physics only (MuJoCo, drives holding): real-time factor %.2f, %.1f us/step\n", seconds / wall,
                  1e6 * wall / static_cast<double>(cycles));
    }
    auto real_time = [&](const char* label, int fifo, double spin) {
      Setup s(urdf);
      s.command_from_another_thread(std::chrono::milliseconds(100));
      concert::robot::LoopParams params;
      params.record_periods = true;
      params.fifo_priority = fifo;
      params.spin_time = spin;
      concert::robot::Loop loop(params, [&] { s.tick(); });
      const auto stats = loop.run(cycles);
      std::printf(
          "real time 1 kHz, %s%s: %llu cycles, period mean %.1f us p99 %.1f us max %.1f us; |jitter| mean %.1f us "
          "p99 %.1f us; overruns %llu\n",
          label, fifo > 0 && !loop.fifo_applied() ? " (SCHED_FIFO not permitted)" : "",
          static_cast<unsigned long long>(stats.cycles), 1e6 * stats.mean_period, 1e6 * stats.p99_period,
          1e6 * stats.max_period, 1e6 * stats.mean_jitter, 1e6 * stats.p99_jitter,
          static_cast<unsigned long long>(stats.overruns));
    };
    real_time("SCHED_FIFO 80 + 200 us spin", 80, 0.0002);
    real_time("plain sleep_until", 0, 0.0);
  } catch (const std::exception& e) {
    std::cerr << "bench_robot: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli(
      "bench_robot",
      "Control-loop period jitter in real-time mode and the simulation's real-time "
      "factor, for the 6-DoF drill arm on the mobile base.",
      std::cout, std::cerr);
  double seconds = 5.0;
  std::string urdf_path = std::string(ROBOT_FIXTURES) + "/mobile_drill.urdf";
  auto& app = cli.app();
  app.add_option("--seconds", seconds, "simulated seconds per run (1 ms cycles)")
      ->capture_default_str()
      ->check(concert::cli::positive_seconds());
  app.add_option("--urdf", urdf_path, "robot model")
      ->capture_default_str()
      ->type_name("FILE")
      ->check(CLI::ExistingFile);
  cli.on_run(app, [&] { return bench(seconds, urdf_path); });
  return cli.run(argc, argv);
}
