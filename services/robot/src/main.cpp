// concert_robot: the robot service (XBot2's role). Simulated hardware by default.
//   concert_robot (--assembly FILE | --urdf FILE) [--module-db DIR ...] [--world FILE]
//                 [--backend sim|ethercat] [--fast] [--duration S] [--ee-frame LINK]
//                 [--standalone] [--fifo PRIORITY] [--package NAME=DIR ...] [--params FILE]
// --params: YAML with sections robot, sim, loop, node (config/robot.yaml); flags override it.
// --assembly and --world are the initial robot and world; later ones come as SimCommands over
// DDS (`concert sim swap FILE`, `concert sim world FILE`, from any host), and the world it
// simulates is published on the latched World topic. See services/robot/README.md.

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "concert/dds/participant.hpp"
#include "robot_node.hpp"
#include "robot_params.hpp"
#include "sim_node.hpp"
#include "robot/loop.hpp"
#include "robot/robot_core.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"

namespace {

constexpr const char* kUsage =
    "usage: concert_robot (--assembly FILE | --urdf FILE) [--module-db DIR ...] [--world FILE] "
    "[--backend sim|ethercat] [--fast] [--duration S] [--ee-frame LINK] [--standalone] [--fifo PRIORITY] [--package NAME=DIR ...] [--params FILE]";

struct Options {
  std::string backend{"sim"};
  std::string assembly;
  std::string urdf;
  std::vector<std::filesystem::path> module_dbs;
  std::string world;
  bool fast{false};
  double duration{0.0};
  std::string ee_frame;
  bool standalone{false};
  int fifo{0};
  std::map<std::string, std::string> packages;
  std::string params;
};

std::atomic<concert::robot::Loop*> g_loop{nullptr};

void on_signal(int) {
  if (auto* loop = g_loop.load()) {
    loop->stop();
  }
}

[[noreturn]] void usage_error(const std::string& what) {
  std::cerr << "concert_robot: " << what << "\n" << kUsage << "\n";
  std::exit(2);
}

double parse_number(const std::string& flag, const std::string& text) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size()) {
      throw std::invalid_argument(text);
    }
    return v;
  } catch (const std::exception&) {
    usage_error(flag + ": expected a number, got '" + text + "'");
  }
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        usage_error(arg + " needs a value");
      }
      return argv[++i];
    };
    if (arg == "--backend") {
      o.backend = value();
    } else if (arg == "--assembly") {
      o.assembly = value();
    } else if (arg == "--urdf") {
      o.urdf = value();
    } else if (arg == "--module-db") {
      o.module_dbs.emplace_back(value());
    } else if (arg == "--world") {
      o.world = value();
    } else if (arg == "--fast") {
      o.fast = true;
    } else if (arg == "--duration") {
      o.duration = parse_number(arg, value());
    } else if (arg == "--ee-frame") {
      o.ee_frame = value();
    } else if (arg == "--standalone") {
      o.standalone = true;
    } else if (arg == "--params") {
      o.params = value();
    } else if (arg == "--package") {
      const std::string v = value();
      const auto eq = v.find('=');
      if (eq == std::string::npos || eq == 0) {
        usage_error("--package: expected NAME=DIR, got '" + v + "'");
      }
      o.packages[v.substr(0, eq)] = v.substr(eq + 1);
    } else if (arg == "--fifo") {
      o.fifo = static_cast<int>(parse_number(arg, value()));
    } else if (arg == "--help" || arg == "-h") {
      std::cout << kUsage << "\n";
      std::exit(0);
    } else {
      usage_error("unknown argument '" + arg + "'");
    }
  }
  if (o.backend == "ethercat") {
    std::cerr << "concert_robot: backend 'ethercat' is not part of this build (no EtherCAT master here); "
                 "see services/robot/README.md for what it must provide\n";
    std::exit(2);
  }
  if (o.backend != "sim") {
    usage_error("unknown backend '" + o.backend + "' (sim or ethercat)");
  }
  if (o.assembly.empty() == o.urdf.empty()) {
    usage_error("give exactly one of --assembly FILE or --urdf FILE");
  }
  if (o.module_dbs.empty()) {
    o.module_dbs.emplace_back(CONCERT_DEFAULT_MODULE_DB);
  }
  if (o.duration < 0.0) {
    usage_error("--duration must not be negative");
  }
  return o;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("cannot open '" + path + "'");
  }
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace concert;
  const Options options = parse(argc, argv);
  try {
    std::optional<sim::AssemblyBuilder> builder;
    sim::SimulatedRobot simulated;
    if (!options.assembly.empty()) {
      builder.emplace(options.module_dbs);
      simulated = builder->build(options.assembly);
    } else {
      simulated.urdf = read_file(options.urdf);
      simulated.source = options.urdf;
    }
    const world::World world = options.world.empty() ? world::World{} : world::load_world_file(options.world);
    robot::dds::ServiceParams service = options.params.empty() ? robot::dds::ServiceParams{}
                                                                : robot::dds::load_service_params(options.params);
    sim::SimParams& sim_params = service.sim;
    // Collision meshes: package://NAME/... resolves to a module-database folder named NAME.
    for (const auto& db : options.module_dbs) {
      sim_params.package_paths[std::filesystem::absolute(db).lexically_normal().filename().string()] =
          std::filesystem::absolute(db).string();
    }
    for (const auto& [name, dir] : options.packages) {
      sim_params.package_paths[name] = dir;
    }
    sim::SimHardware sim(simulated.urdf, world, sim_params);
    robot::RobotParams& params = service.robot;
    if (!options.ee_frame.empty()) {
      params.end_effector_frame = options.ee_frame;
    }
    robot::RobotCore core(sim, params);

    concert::dds::Participant participant({.name = "robot"});
    robot::dds::RobotNode node(participant, core, service.node);
    if (!options.assembly.empty()) {
      node.publish_scan(simulated.scan, "sim");
    }
    if (options.standalone) {
      node.apply_model(simulated.urdf, 1, options.ee_frame);
    }

    robot::LoopParams& loop_params = service.loop;
    if (options.fast) {
      loop_params.real_time = false;
    }
    if (options.fifo > 0) {
      loop_params.fifo_priority = options.fifo;
    }
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
        }
        next += std::chrono::microseconds(static_cast<long>(1e6 * params.period));
        std::this_thread::sleep_until(next);
      }
    });
    // Hot swaps and world changes come as SimCommands over DDS (`concert sim swap/world`):
    // prepared on the sim node's worker thread, switched in by the loop at a cycle boundary.
    robot::dds::SimNode sim_node(
        participant, sim, builder ? &*builder : nullptr, node, world, options.world.empty() ? "empty world" : options.world,
        [&](const sim::SimulatedRobot& mounted) {
          if (options.standalone) {
            node.apply_model(mounted.urdf, core.model_version() + 1, options.ee_frame);
          }
        });
    robot::Loop loop(loop_params, [&] { core.cycle(); });
    g_loop = &loop;
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    const auto cycles = options.duration > 0.0 ? static_cast<std::uint64_t>(options.duration / params.period)
                                                : std::numeric_limits<std::uint64_t>::max();
    const robot::LoopStats stats = loop.run(cycles);
    g_loop = nullptr;
    stopping = true;
    publisher.join();
    std::cerr << "concert_robot: stopped after " << stats.cycles << " cycles (" << stats.overruns << " overruns)\n";
  } catch (const std::exception& e) {
    std::cerr << "concert_robot: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
