// concert_ecat_ring: the EtherCAT ring of an assembly file, answering frames on a network
// interface until SIGINT/SIGTERM (libs/ethercat VirtualRing over a raw socket).
//   concert_ecat_ring --assembly FILE --ifname IF [--module-db DIR ...] [--process-data FILE]
//                     [--robot [--world FILE]] [--eeprom-8-byte]
//                     [--fault pull:MODULE@S | refuse-op:MODULE[:CODE] | lose:N ...]
// The assembly's faults (libs/simbus README: upside_down, broken_link, unknown_identity,
// wrong_topology) are on the ring as a master meets them; --fault adds run-time ones (README of
// libs/ethercat). SIGHUP re-reads the assembly file: a module added or removed while running.
// Needs root or CAP_NET_RAW.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/ethercat/link.hpp"
#include "concert/ethercat/robot_on_ring.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/world/world.hpp"
#include <filesystem>
#include "concert/ethercat/virtual_ring.hpp"
#include "concert/simbus/assembly.hpp"

namespace {

std::atomic<bool> g_reload{false};
void on_hangup(int) { g_reload = true; }

/// A run-time fault of --fault.
struct RingFault {
  enum Kind { kPull, kRefuseOp, kLose } kind = kPull;
  std::string module;
  double after_s = 0;   // pull: seconds after the first process data frame
  uint16_t code = 0x001A;
  uint64_t one_in = 0;
  bool done = false;
};

RingFault parse_fault(const std::string& spec) {
  RingFault f;
  const auto colon = spec.find(':');
  if (colon == std::string::npos) throw concert::cli::UsageError("--fault " + spec + ": expected KIND:ARGUMENT");
  const std::string kind = spec.substr(0, colon);
  const std::string arg = spec.substr(colon + 1);
  const auto number = [&](const std::string& text, const char* what) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || v < 0) {
      throw concert::cli::UsageError("--fault " + spec + ": " + what + " '" + text + "' is not a number >= 0");
    }
    return v;
  };
  if (kind == "pull") {
    f.kind = RingFault::kPull;
    const auto at = arg.find('@');
    f.module = arg.substr(0, at);
    if (at != std::string::npos) f.after_s = number(arg.substr(at + 1), "seconds");
  } else if (kind == "refuse-op") {
    f.kind = RingFault::kRefuseOp;
    const auto c = arg.find(':');
    f.module = arg.substr(0, c);
    if (c != std::string::npos) f.code = static_cast<uint16_t>(std::stoul(arg.substr(c + 1), nullptr, 0));
  } else if (kind == "lose") {
    f.kind = RingFault::kLose;
    f.one_in = static_cast<uint64_t>(number(arg, "N"));
    if (f.one_in < 2) throw concert::cli::UsageError("--fault " + spec + ": lose:N needs N >= 2");
  } else {
    throw concert::cli::UsageError("--fault " + spec + ": kind '" + kind + "' is not pull, refuse-op or lose");
  }
  if (f.kind != RingFault::kLose && f.module.empty()) {
    throw concert::cli::UsageError("--fault " + spec + ": no module named");
  }
  return f;
}

struct Options {
  std::string assembly;
  std::string ifname;
  std::vector<std::string> module_dbs;
  std::string process_data = CONCERT_DEFAULT_PROCESS_DATA;
  bool eeprom_8_byte = false;
  std::vector<std::string> faults;
  bool robot = false;
  std::string world;
};

int run(const Options& o) {
  using namespace concert;
  std::vector<std::string> dbs = o.module_dbs;
  if (dbs.empty()) dbs.push_back(CONCERT_DEFAULT_MODULE_DB);
  topology::EscCatalog catalog = topology::EscCatalog::load(dbs.front());
  for (std::size_t i = 1; i < dbs.size(); ++i) catalog.merge(topology::EscCatalog::load(dbs[i]));
  const simbus::Assembly assembly = simbus::load_assembly(o.assembly);
  const ethercat::ProcessDataCatalog process_data = ethercat::ProcessDataCatalog::load(o.process_data);
  ethercat::VirtualRing ring(assembly, catalog,
                             ethercat::RingParams{.eeprom_8_byte_reads = o.eeprom_8_byte}, &process_data);
  // --robot: the MuJoCo robot of the assembly behind the drive boards.
  std::optional<sim::SimHardware> simulated;
  std::optional<ethercat::RobotOnRing> robot;
  if (o.robot) {
    const sim::AssemblyBuilder builder(std::vector<std::filesystem::path>(dbs.begin(), dbs.end()));
    sim::SimulatedRobot mounted = builder.build(o.assembly);
    const ethercat::BoardProcessData* drive = process_data.find(21);
    if (!drive) throw cli::Failure(o.process_data + ": no drive board (ESC type 21) to put the robot behind");
    sim::SimParams params;
    params.sensors.enabled = false;  // the ring carries the drives only
    const world::World world = o.world.empty() ? world::World{} : world::load_world_file(o.world);
    simulated.emplace(mounted, world, params);
    robot.emplace(*simulated, mounted, *drive);
    ring.set_application([&robot](std::span<ethercat::BoardIo> boards, uint64_t now) { robot->exchange(boards, now); });
    std::cerr << "concert_ecat_ring: the MuJoCo robot of " << o.assembly << " (" << simulated->joint_names().size()
              << " joints) behind the drive boards" << (o.world.empty() ? "" : ", in " + o.world) << std::endl;
  }
  std::vector<RingFault> faults;
  for (const std::string& spec : o.faults) faults.push_back(parse_fault(spec));
  for (RingFault& f : faults) {
    if (f.kind == RingFault::kRefuseOp) ring.refuse_op(f.module, f.code);
    if (f.kind == RingFault::kLose) ring.lose_one_in(f.one_in);
    if (f.kind == RingFault::kPull) {
      // Checked now, so a misspelt module fails at start, not minutes later.
      if (std::none_of(assembly.modules.begin(), assembly.modules.end(),
                       [&](const simbus::MountedModule& m) { return m.name == f.module; })) {
        throw cli::UsageError("--fault pull:" + f.module + ": no module '" + f.module + "' in " + o.assembly);
      }
    }
  }
  ethercat::RawSocketLink link(o.ifname);
  const std::atomic<bool>& stop = cli::stop_on_signals();
  std::signal(SIGHUP, on_hangup);
  std::optional<std::chrono::steady_clock::time_point> first_process_data;
  std::cerr << "concert_ecat_ring: serving " << ring.slave_count() << " ESCs of " << o.assembly
            << " on " << o.ifname << " (" << ethercat::to_string(link.mac()) << "); process data of "
            << o.process_data << (o.robot ? "" : " (no robot behind the boards: their inputs stay zero; --robot)")
            << std::endl;
  const auto start = std::chrono::steady_clock::now();
  uint64_t reported_malformed = 0;
  bool warned_unmatched = false;
  while (!stop) {
    const auto frame = link.receive(std::chrono::milliseconds(100));
    if (g_reload.exchange(false)) {
      try {
        const std::size_t before = ring.slave_count();
        ring.set_assembly(simbus::load_assembly(o.assembly));
        std::cerr << "concert_ecat_ring: re-read " << o.assembly << ": " << before << " -> "
                  << ring.slave_count() << " ESCs" << std::endl;
      } catch (const std::exception& e) {
        std::cerr << "concert_ecat_ring: re-reading " << o.assembly << " failed, the ring stays as it was: "
                  << e.what() << std::endl;
      }
    }
    if (first_process_data) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - *first_process_data).count();
      for (RingFault& f : faults) {
        if (f.kind == RingFault::kPull && !f.done && s >= f.after_s) {
          ring.pull_cable(f.module);
          f.done = true;
          std::cerr << "concert_ecat_ring: pulled the cable of '" << f.module << "' after " << s
                    << " s of process data: " << ring.slave_count() << " ESCs answer" << std::endl;
        }
      }
    }
    if (!frame) continue;
    // The first logical datagram starts the clock of the timed faults.
    if (!first_process_data && frame->size() > 16 && (*frame)[16] >= 10 && (*frame)[16] <= 12) {
      first_process_data = std::chrono::steady_clock::now();
    }
    const auto now = static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                               std::chrono::steady_clock::now() - start)
                                               .count());
    if (auto answer = ring.process(*frame, now)) link.send(*answer);
    if (robot && !robot->unmatched().empty() && !warned_unmatched) {
      warned_unmatched = true;
      std::cerr << "concert_ecat_ring: " << robot->unmatched().size()
                << " joints found no drive board in OP (first: " << robot->unmatched().front() << ")" << std::endl;
    }
    const auto& c = ring.counters();
    if (c.malformed > reported_malformed) {
      reported_malformed = c.malformed;
      // The first few, then every thousandth: a flood of noise must not flood the log.
      if (reported_malformed <= 5 || reported_malformed % 1000 == 0) {
        std::cerr << "concert_ecat_ring: dropped frame " << reported_malformed
                  << " that is not EtherCAT: " << c.last_error << std::endl;
      }
    }
  }
  const auto& c = ring.counters();
  std::cerr << "concert_ecat_ring: stopped after " << c.frames << " frames (" << c.datagrams
            << " datagrams), " << c.malformed << " dropped as malformed, " << c.lost
            << " lost on purpose" << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli("concert_ecat_ring",
                        "Serves the EtherCAT ring of an assembly file on a network interface, frame "
                        "by frame, until Ctrl-C (needs root or CAP_NET_RAW).",
                        std::cout, std::cerr);
  Options o;
  CLI::App& app = cli.app();
  app.add_option("--assembly", o.assembly, "assembly file (libs/simbus README), faults included")
      ->type_name("FILE")
      ->required();
  app.add_option("--ifname", o.ifname, "network interface the master's frames arrive on")
      ->type_name("IF")
      ->required();
  app.add_option("--module-db", o.module_dbs,
                 "module database folder (repeat to merge; default: the project's)")
      ->type_name("DIR");
  app.add_option("--process-data", o.process_data, "process data of each board type")
      ->type_name("FILE")
      ->capture_default_str();
  app.add_option("--fault", o.faults,
                 "a run-time fault (repeatable): pull:MODULE@S (the cable from MODULE to its parent "
                 "pulled S s after the first process data frame), refuse-op:MODULE[:CODE] (its "
                 "boards stay in SAFE-OP with AL status CODE, default 0x001A), lose:N (one frame "
                 "in N lost)")
      ->type_name("SPEC");
  app.add_flag("--robot", o.robot,
               "the assembly's MuJoCo robot (libs/sim) behind the drive boards: their outputs drive "
               "it, one millisecond of physics per process data frame, their inputs report it");
  app.add_option("--world", o.world, "the robot's world (with --robot)")->type_name("FILE");
  app.add_flag("--eeprom-8-byte", o.eeprom_8_byte,
               "ESCs read 8 bytes of EEPROM per command (default 4)");
  cli.on_run(app, [&o] { return run(o); });
  return cli.run(argc, argv);
}
