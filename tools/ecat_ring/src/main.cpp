// concert_ecat_ring: the EtherCAT ring of an assembly file, answering frames on a network
// interface until SIGINT/SIGTERM (libs/ethercat VirtualRing and RingServer over a raw socket).
//   concert_ecat_ring --assembly FILE --ifname IF [--module-db DIR ...] [--process-data FILE]
//                     [--fault pull:MODULE@S | refuse-op:MODULE[:CODE] | lose:N ...]
//                     [--robot [--world FILE]] [--eeprom-8-byte]
// The assembly's faults (libs/simbus README) are on the ring as a master meets them; --fault adds
// run-time ones (libs/ethercat README). SIGHUP re-reads the assembly file: a module added or
// removed while running. Needs root or CAP_NET_RAW.
#include <atomic>
#include <csignal>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/ethercat/link.hpp"
#include "concert/ethercat/ring_server.hpp"
#include "concert/ethercat/robot_on_ring.hpp"
#include "concert/ethercat/virtual_ring.hpp"
#include "concert/simbus/assembly.hpp"

namespace {

std::atomic<bool> g_reload{false};
void on_hangup(int) { g_reload = true; }

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
  std::vector<ethercat::RingFault> faults;
  try {
    for (const std::string& spec : o.faults) faults.push_back(ethercat::parse_ring_fault(spec));
  } catch (const ethercat::RingFaultError& e) {
    throw cli::UsageError(e.what());
  }
  const ethercat::ProcessDataCatalog process_data = ethercat::ProcessDataCatalog::load(o.process_data);
  ethercat::VirtualRing ring(simbus::load_assembly(o.assembly), catalog,
                             ethercat::RingParams{.eeprom_8_byte_reads = o.eeprom_8_byte}, &process_data);
  std::unique_ptr<ethercat::RobotBehindRing> robot;
  if (o.robot) {
    robot = std::make_unique<ethercat::RobotBehindRing>(ring, dbs, o.assembly, o.world, process_data);
    std::cerr << "concert_ecat_ring: the MuJoCo robot of " << o.assembly << " (" << robot->joints()
              << " joints) behind the drive boards" << (o.world.empty() ? "" : ", in " + o.world) << std::endl;
  }
  ethercat::RawSocketLink link(o.ifname);
  ethercat::RingServer server(ring, link, std::move(faults), std::cerr);
  const std::atomic<bool>& stop = cli::stop_on_signals();
  std::signal(SIGHUP, on_hangup);
  std::cerr << "concert_ecat_ring: serving " << ring.slave_count() << " ESCs of " << o.assembly << " on "
            << o.ifname << " (" << ethercat::to_string(link.mac()) << "); process data of " << o.process_data
            << (o.robot ? "" : " (no robot behind the boards: their inputs stay zero; --robot)") << std::endl;
  server.serve(stop, g_reload, [&o] { return simbus::load_assembly(o.assembly); });
  if (robot && !robot->robot().unmatched().empty()) {
    std::cerr << "concert_ecat_ring: " << robot->robot().unmatched().size()
              << " joints found no drive board in the last frame (first: " << robot->robot().unmatched().front()
              << ")" << std::endl;
  }
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
  app.add_option("--module-db", o.module_dbs, "module database folder (repeat to merge; default: the project's)")
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
  app.add_flag("--eeprom-8-byte", o.eeprom_8_byte, "ESCs read 8 bytes of EEPROM per command (default 4)");
  cli.on_run(app, [&o] { return run(o); });
  return cli.run(argc, argv);
}
