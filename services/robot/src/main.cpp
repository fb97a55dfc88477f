// concert_robot: the robot service (XBot2's role). Simulated hardware by default.
//   concert_robot (--assembly FILE | --urdf FILE) [--module-db DIR ...] [--world FILE]
//                 [--backend sim|ethercat] [--fast] [--duration S] [--ee-frame LINK]
//                 [--standalone] [--fifo PRIORITY] [--package NAME=DIR ...] [--params FILE]
// --params: YAML with sections robot, sim, loop, node (config/robot.yaml); flags override it.
// The assembly and world files are watched: edit them (hot swap, new walls) while it runs
// and the simulated bus publishes the new scan. See services/robot/README.md.
#include <sys/stat.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/dds/participant.hpp"
#include "robot/loop.hpp"
#include "robot/robot_core.hpp"
#include "robot/sim_assembly.hpp"
#include "robot/sim_hardware.hpp"
#include "robot_node.hpp"
#include "robot_params.hpp"

namespace {

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
  app.add_option("--backend", o.backend, "hardware backend")
      ->type_name("sim|ethercat")
      ->default_str("sim");
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
  app.add_option("--params", o.params, "parameters file (config/robot.yaml lists every key)")
      ->type_name("FILE");
}

/// Checks of the parsed options that involve several of them.
void check(Options& o) {
  if (o.backend == "ethercat") {
    throw concert::cli::UsageError(
        "backend 'ethercat' is not part of this build (no EtherCAT master here); "
        "see services/robot/README.md for what it must provide");
  }
  if (o.backend != "sim") {
    throw concert::cli::UsageError("unknown backend '" + o.backend + "' (sim or ethercat)");
  }
  if (o.assembly.empty() == o.urdf.empty()) {
    throw concert::cli::UsageError("give exactly one of --assembly FILE or --urdf FILE");
  }
  if (o.module_dbs.empty()) {
    o.module_dbs.emplace_back(CONCERT_DEFAULT_MODULE_DB);
  }
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

std::optional<std::filesystem::file_time_type> mtime(const std::string& path) {
  std::error_code ec;
  const auto t = std::filesystem::last_write_time(path, ec);
  if (ec) {
    return std::nullopt;
  }
  return t;
}

int run(const Options& options) {
  using namespace concert;
  {
    std::optional<robot::AssemblyBuilder> builder;
    robot::SimulatedRobot simulated;
    if (!options.assembly.empty()) {
      builder.emplace(options.module_dbs);
      simulated = builder->build(options.assembly);
    } else {
      simulated.urdf = read_file(options.urdf);
      simulated.source = options.urdf;
    }
    const robot::World world = options.world.empty() ? robot::World{} : robot::load_world_file(options.world);
    robot::dds::ServiceParams service = options.params.empty() ? robot::dds::ServiceParams{}
                                                                : robot::dds::load_service_params(options.params);
    robot::SimParams& sim_params = service.sim;
    // Collision meshes: package://NAME/... resolves to a module-database folder named NAME.
    for (const auto& db : options.module_dbs) {
      sim_params.package_paths[std::filesystem::absolute(db).lexically_normal().filename().string()] =
          std::filesystem::absolute(db).string();
    }
    for (const auto& [name, dir] : options.packages) {
      sim_params.package_paths[name] = dir;
    }
    robot::SimHardware sim(simulated.urdf, world, sim_params);
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
    auto watched = options.assembly.empty() ? std::nullopt : mtime(options.assembly);
    auto world_watched = options.world.empty() ? std::nullopt : mtime(options.world);
    std::uint64_t ticks = 0;
    robot::Loop loop(loop_params, [&] {
      // Hot swap: the assembly file changed (checked every 250 ms of loop time).
      ++ticks;
      if (!options.assembly.empty() && ticks % 250 == 0) {
        const auto now = mtime(options.assembly);
        if (now && now != watched) {
          watched = now;
          try {
            simulated = builder->build(options.assembly);
            sim.swap_model(simulated.urdf);
            core.cycle();  // the core notices the new hardware before anyone sees the scan
            node.publish_scan(simulated.scan, "sim");
            std::cerr << "concert_robot: hot swap from '" << options.assembly << "': " << simulated.scan.slaves.size()
                      << " slaves\n";
            if (options.standalone) {
              node.apply_model(simulated.urdf, core.model_version() + 1, options.ee_frame);
            }
          } catch (const std::exception& e) {
            std::cerr << "concert_robot: hot swap refused, the robot keeps its modules: " << e.what() << "\n";
          }
        }
      }
      // World edits (walls, obstacles) are picked up the same way.
      if (!options.world.empty() && ticks % 250 == 125) {
        const auto now = mtime(options.world);
        if (now && now != world_watched) {
          world_watched = now;
          try {
            sim.set_world(robot::load_world_file(options.world));
            std::cerr << "concert_robot: world reloaded from '" << options.world << "'\n";
          } catch (const std::exception& e) {
            std::cerr << "concert_robot: world change refused, the old world stays: " << e.what() << "\n";
          }
        }
      }
      core.cycle();
      node.publish(core.state());
    });
    g_loop = &loop;
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    const auto cycles = options.duration > 0.0 ? static_cast<std::uint64_t>(options.duration / params.period)
                                                : std::numeric_limits<std::uint64_t>::max();
    const robot::LoopStats stats = loop.run(cycles);
    g_loop = nullptr;
    std::cerr << "concert_robot: stopped after " << stats.cycles << " cycles (" << stats.overruns
              << " overruns)\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
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
