// concert_robot: the robot service (XBot2's role). Simulated hardware by default.
//   concert_robot (--assembly FILE | --urdf FILE) [--module-db DIR ...] [--world FILE]
//                 [--backend sim] [--fast] [--duration S] [--ee-frame LINK]
//                 [--standalone] [--fifo PRIORITY] [--package NAME=DIR ...] [--safety-timeout S] [--params FILE]
//                 [--keep-swaps]
//   concert_robot --backend ethercat --ifname IF [--process-data FILE] [--duration S] [--ee-frame LINK]
//                 [--fifo PRIORITY] [--safety-timeout S] [--params FILE]
// --params: YAML with sections robot, sim, loop, node (config/robot.yaml); flags override it.
// --assembly and --world are the initial robot and world; later ones come as SimCommands over
// DDS (`concert sim swap FILE`, `concert sim world FILE`, from any host), and the world it
// simulates is published on the latched World topic. See services/robot/README.md.

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/common/text.hpp"
#include "concert/dds/participant.hpp"
#include "concert/ethercat/ethercat_hardware.hpp"
#include "concert/ethercat/link.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "robot/loop.hpp"
#include "robot/robot_core.hpp"
#include "robot_node.hpp"
#include "robot_params.hpp"
#include "sensor_publisher.hpp"
#include "sim_node.hpp"

namespace {

struct Options {
  std::string backend{"sim"};
  std::string ifname;        // ethercat: the ring's network interface
  std::string process_data;  // ethercat: process data of each board type
  std::string assembly;
  std::string urdf;
  std::vector<std::filesystem::path> module_dbs;
  std::string world;
  bool keep_swaps{false};
  bool fast{false};
  double duration{0.0};
  std::string ee_frame;
  bool standalone{false};
  int fifo{0};
  double safety_timeout{-1.0};  // < 0: the parameters file's (node.safety_timeout)
  std::map<std::string, std::string> packages;
  std::string params;
};

std::atomic<concert::robot::Loop*> g_loop{nullptr};

/// Registers a sensor sink with a backend for the registration's lifetime.
class SensorSinkRegistration {
 public:
  SensorSinkRegistration(concert::hardware::Hardware& hardware, concert::hardware::SensorSink& sink)
      : hardware_(hardware) {
    hardware_.set_sensor_sink(&sink);
  }
  ~SensorSinkRegistration() { hardware_.set_sensor_sink(nullptr); }
  SensorSinkRegistration(const SensorSinkRegistration&) = delete;
  SensorSinkRegistration& operator=(const SensorSinkRegistration&) = delete;

 private:
  concert::hardware::Hardware& hardware_;
};

/// The backend's sensor data to DDS, and the base's IMU also to the core (its odometry's yaw).
class SensorFanOut final : public concert::hardware::SensorSink {
 public:
  SensorFanOut(concert::hardware::SensorSink& publisher, concert::robot::RobotCore& core)
      : publisher_(publisher), core_(core) {}
  void on_sensors(const std::vector<concert::hardware::SensorInfo>& mounted) override {
    publisher_.on_sensors(mounted);
  }
  void on_rgbd(const concert::hardware::RgbdFrame& frame) override { publisher_.on_rgbd(frame); }
  void on_lidar(const concert::hardware::LidarScan& scan) override { publisher_.on_lidar(scan); }
  void on_scan2d(const concert::hardware::LaserScan2d& scan) override {
    publisher_.on_scan2d(scan);
  }
  void on_sonars(const concert::hardware::SonarRanges& ranges) override {
    publisher_.on_sonars(ranges);
  }
  void on_imu(const concert::hardware::ImuSample& sample) override {
    core_.on_imu(sample);
    publisher_.on_imu(sample);
  }

 private:
  concert::hardware::SensorSink& publisher_;
  concert::robot::RobotCore& core_;
};

void on_signal(int) {
  if (auto* loop = g_loop.load()) {
    loop->stop();
  }
}

/// The command line (CLI11); what it cannot check alone is checked in check().
void add_options(CLI::App& app, Options& o) {
  CLI::Option* assembly =
      app.add_option("--assembly", o.assembly,
                     "the mounted modules (an assembly file; watched for hot swaps)")
          ->type_name("FILE");
  CLI::Option* urdf = app.add_option("--urdf", o.urdf, "a fixed robot model instead of an assembly")
                          ->type_name("FILE");
  assembly->excludes(urdf);
  app.add_option("--module-db", o.module_dbs,
                 "module database folder (repeat to merge; default: the project's)")
      ->type_name("DIR");
  app.add_option("--world", o.world, "the simulated world (walls, obstacles; watched)")
      ->type_name("FILE");
  app.add_flag("--keep-swaps", o.keep_swaps,
               "write each accepted hot swap and world over the --assembly and --world files, so "
               "that a restarted simulator mounts the same modules in the same world");
  app.add_option("--backend", o.backend, "hardware backend")
      ->type_name("sim|ethercat")
      ->default_str("sim");
  app.add_option("--ifname", o.ifname, "ethercat: the network interface of the ring")
      ->type_name("IF");
  app.add_option("--process-data", o.process_data,
                 "ethercat: process data of each board type (default: the project's "
                 "data/module_db/process_data.yaml)")
      ->type_name("FILE");
  app.add_flag("--fast", o.fast, "run as fast as possible (simulated time only)");
  app.add_option("--duration", o.duration,
                 "stop after S seconds of loop time (0: run until stopped)")
      ->type_name("S")
      ->check(concert::cli::seconds());
  app.add_option("--ee-frame", o.ee_frame, "the Cartesian end-effector frame")->type_name("LINK");
  app.add_flag("--standalone", o.standalone, "apply the model itself, without modelgen");
  app.add_option("--fifo", o.fifo, "SCHED_FIFO priority of the loop (1..99)")
      ->type_name("PRIORITY")
      ->check(concert::cli::number(0, 99, true));
  app.add_option_function<std::vector<std::string>>(
         "--package",
         [&o](const std::vector<std::string>& items) {
           for (const auto& v : items)
             o.packages[v.substr(0, v.find('='))] = v.substr(v.find('=') + 1);
         },
         "package://NAME/ resolves to DIR (repeat)")
      ->type_name("NAME=DIR")
      ->check(CLI::Validator(
          [](std::string& v) {
            const auto eq = v.find('=');
            return eq == std::string::npos || eq == 0 ? "expected NAME=DIR, got '" + v + "'"
                                                      : std::string();
          },
          "", "NAME=DIR"));
  app.add_option("--safety-timeout", o.safety_timeout,
                 "hold until the safety service is heard and whenever it is silent this long "
                 "(0: not required; default: node.safety_timeout of --params, 0)")
      ->type_name("S")
      ->check(concert::cli::seconds());
  app.add_option("--params", o.params, "parameters file (config/robot.yaml lists every key)")
      ->type_name("FILE");
}

/// Checks of the parsed options that involve several of them.
void check(Options& o) {
  if (o.backend != "sim" && o.backend != "ethercat") {
    throw concert::cli::UsageError("unknown backend '" + o.backend + "' (sim or ethercat)");
  }
  if (o.backend == "ethercat") {
    // The ring is the robot: no simulated robot, world or model of its own.
    if (o.ifname.empty()) throw concert::cli::UsageError("--backend ethercat needs --ifname IF (the ring's interface)");
    for (const auto& [given, flag] : {std::pair{!o.assembly.empty(), "--assembly"}, {!o.urdf.empty(), "--urdf"},
                                      {!o.world.empty(), "--world"}, {o.standalone, "--standalone"},
                                      {o.keep_swaps, "--keep-swaps"}, {o.fast, "--fast"}}) {
      if (given) throw concert::cli::UsageError(std::string(flag) + " is the simulator's: not with --backend ethercat");
    }
    if (o.process_data.empty()) o.process_data = CONCERT_DEFAULT_PROCESS_DATA;
    return;
  }
  if (!o.ifname.empty() || !o.process_data.empty()) {
    throw concert::cli::UsageError("--ifname and --process-data are the ethercat backend's (--backend ethercat)");
  }
  if (o.assembly.empty() == o.urdf.empty()) {
    throw concert::cli::UsageError("give exactly one of --assembly FILE or --urdf FILE");
  }
  if (o.keep_swaps && (o.assembly.empty() || o.world.empty())) {
    throw concert::cli::UsageError("--keep-swaps writes over the --assembly and --world files: give both");
  }
  if (o.module_dbs.empty()) {
    o.module_dbs.emplace_back(CONCERT_DEFAULT_MODULE_DB);
  }
}

/// The service's parameters (--params, else the defaults) with what the command line overrides:
/// the module databases' mesh packages, the end-effector frame, the safety timeout, the loop's
/// real-time settings.
concert::robot::dds::ServiceParams service_params(const Options& options) {
  using namespace concert;
  robot::dds::ServiceParams service =
      options.params.empty() ? robot::dds::ServiceParams{} : robot::dds::load_service_params(options.params);
  // Collision meshes: package://NAME/... resolves to a module-database folder named NAME.
  for (const auto& db : options.module_dbs) {
    service.sim.package_paths[std::filesystem::absolute(db).lexically_normal().filename().string()] =
        std::filesystem::absolute(db).string();
  }
  for (const auto& [name, dir] : options.packages) service.sim.package_paths[name] = dir;
  if (!options.ee_frame.empty()) service.robot.end_effector_frame = options.ee_frame;
  if (options.safety_timeout >= 0.0) service.node.safety_timeout = options.safety_timeout;
  if (options.fast) service.loop.real_time = false;
  if (options.fifo > 0) service.loop.fifo_priority = options.fifo;
  return service;
}

// Every 10 s of wall time until `stopping`, the log says how fast simulated time runs: the
// loop's lag behind the wall clock on a loaded machine (no cycle is late in simulated time).
std::thread timing_reporter(const concert::robot::Loop& loop, double period, const std::atomic<bool>& stopping) {
  return std::thread([&loop, period, &stopping] {
    using Clock = std::chrono::steady_clock;
    using concert::robot::LoopProgress;
    auto since = Clock::now();
    LoopProgress before = loop.progress();
    while (!stopping.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      const auto now = Clock::now();
      const double wall = std::chrono::duration<double>(now - since).count();
      if (wall < 10.0) continue;
      const LoopProgress p = loop.progress();
      std::cerr << "concert_robot: " << concert::robot::simulated_time_line(before, p, wall, period) << std::endl;
      before = p;
      since = now;
    }
  });
}

/// The loop until stopped (signal, --duration), with the publisher that hands its state to DDS
/// and the timing reporter; `sensors` (none without sensors) follows the model version.
void run_loop(concert::robot::RobotCore& core, concert::robot::dds::RobotNode& node,
              concert::robot::dds::SensorPublisher* sensors, const concert::robot::dds::ServiceParams& service,
              const Options& options) {
  using namespace concert;
  const robot::RobotParams& params = service.robot;
  robot::Loop loop(service.loop, [&] { core.cycle(); });
  // Off the loop thread: the publisher hands the loop's state to DDS.
  std::atomic<bool> stopping{false};
  std::thread publisher([&] {
    std::uint64_t last = 0;
    auto next = std::chrono::steady_clock::now();
    while (!stopping.load()) {
      const robot::RobotState state = core.state();
      if (state.cycle != last) {
        last = state.cycle;
        node.publish(state);
        if (sensors != nullptr) sensors->set_model_version(static_cast<std::uint32_t>(state.model_version));
      }
      next += std::chrono::microseconds(static_cast<long>(1e6 * params.period));
      std::this_thread::sleep_until(next);
    }
  });
  g_loop = &loop;
  concert::cli::on_stop_signals(on_signal);
  const auto cycles = options.duration > 0.0 ? static_cast<std::uint64_t>(options.duration / params.period)
                                              : std::numeric_limits<std::uint64_t>::max();
  std::thread timing;
  const auto stop = [&] {
    g_loop = nullptr;
    stopping = true;
    publisher.join();
    if (timing.joinable()) timing.join();
  };
  robot::LoopStats stats;
  try {
    timing = timing_reporter(loop, params.period, stopping);
    stats = loop.run(cycles);
  } catch (...) {
    stop();
    throw;
  }
  stop();
  std::cerr << "concert_robot: stopped: "
            << robot::simulated_time_line({}, {stats.cycles, stats.overruns}, stats.wall_time, params.period) << "\n";
}

/// The robot on an EtherCAT ring: the master scans it and brings it to OP (every drive
/// disabled), publishes the scan, and binds the joints of each model modelgen sends to the drive
/// boards by their modules' robot_ids (a joint with no board refuses the model, naming it).
int run_ethercat(const Options& options) {
  using namespace concert;
  ethercat::RawSocketLink link(options.ifname);
  ethercat::EthercatHardware hw(link, ethercat::ProcessDataCatalog::load(options.process_data));
  const ethercat::ScanReport& report = hw.scan();
  std::cerr << "concert_robot: ethercat on " << options.ifname << ": " << report.slaves.size()
            << " slaves, in OP, every drive disabled until a model binds its joints" << std::endl;
  robot::dds::ServiceParams service = service_params(options);
  robot::RobotCore core(hw, service.robot);
  concert::dds::Participant participant({.name = "robot"});
  robot::dds::RobotNode node(participant, core, service.node, [&hw](const model::ModelDescription& d) {
    std::vector<std::string> joints;
    for (const model::JointLimits& j : d.joints) joints.push_back(j.name);
    hw.prepare_joints(ethercat::model_binding(d.config_yaml, joints));
  });
  node.publish_scan(report.scan(), "ethercat " + options.ifname);
  run_loop(core, node, nullptr, service, options);
  return 0;
}

int run(const Options& options) {
  if (options.backend == "ethercat") return run_ethercat(options);
  using namespace concert;
  {
    std::optional<sim::AssemblyBuilder> builder;
    sim::SimulatedRobot simulated;
    if (!options.assembly.empty()) {
      builder.emplace(options.module_dbs);
      simulated = builder->build(options.assembly);
    } else {
      simulated.urdf = concert::read_file(options.urdf, "URDF");
      simulated.source = options.urdf;
    }
    const world::World world = options.world.empty() ? world::World{} : world::load_world_file(options.world);
    robot::dds::ServiceParams service = service_params(options);
    sim::SimHardware sim(simulated, world, service.sim);
    robot::RobotParams& params = service.robot;
    robot::RobotCore core(sim, params);

    concert::dds::Participant participant({.name = "robot"});
    robot::dds::RobotNode node(participant, core, service.node);
    // The backend's sensor threads hand their data to DDS from now on, until the registration
    // (made after the publisher, so gone before it, also on an exception) unsets it.
    robot::dds::SensorPublisher sensors(participant, static_cast<std::uint32_t>(core.model_version()));
    SensorFanOut fan_out(sensors, core);
    const SensorSinkRegistration registration(sim, fan_out);
    if (!options.assembly.empty()) {
      node.publish_scan(simulated.scan, "sim");
    }
    if (options.standalone) {
      node.apply_model(simulated.urdf, 1, options.ee_frame);
    }

    // Hot swaps and world changes come as SimCommands over DDS (`concert sim swap/world`):
    // prepared on the sim node's worker thread, switched in by the loop at a cycle boundary.
    robot::dds::SimNode sim_node(
        participant, sim, builder ? &*builder : nullptr, node, world, options.world.empty() ? "empty world" : options.world,
        [&](const sim::SimulatedRobot& mounted) {
          if (options.standalone) {
            node.apply_model(mounted.urdf, core.model_version() + 1, options.ee_frame);
          }
        },
        options.keep_swaps ? robot::dds::SimNode::Keep{options.assembly, options.world}
                           : robot::dds::SimNode::Keep{});
    run_loop(core, node, &sensors, service, options);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli(
      "concert_robot",
      "The robot service: hardware abstraction (simulated by default), 1 kHz loop.", std::cout,
      std::cerr);
  Options options;
  add_options(cli.app(), options);
  cli.on_run(cli.app(), [&options] {
    check(options);
    return run(options);
  });
  return cli.run(argc, argv);
}
