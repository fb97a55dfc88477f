// concert_ecat_ring: the EtherCAT ring of an assembly file, answering frames on a network
// interface until SIGINT/SIGTERM (libs/ethercat VirtualRing over a raw socket).
//   concert_ecat_ring --assembly FILE --ifname IF [--module-db DIR ...] [--process-data FILE]
//                     [--eeprom-8-byte]
// The assembly's faults (libs/simbus README: upside_down, broken_link, unknown_identity,
// wrong_topology) are on the ring as a master meets them. Needs root or CAP_NET_RAW.
#include <chrono>
#include <iostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/ethercat/link.hpp"
#include "concert/ethercat/virtual_ring.hpp"
#include "concert/simbus/assembly.hpp"

namespace {

struct Options {
  std::string assembly;
  std::string ifname;
  std::vector<std::string> module_dbs;
  std::string process_data = CONCERT_DEFAULT_PROCESS_DATA;
  bool eeprom_8_byte = false;
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
  ethercat::RawSocketLink link(o.ifname);
  const std::atomic<bool>& stop = cli::stop_on_signals();
  std::cerr << "concert_ecat_ring: serving " << ring.slave_count() << " ESCs of " << o.assembly
            << " on " << o.ifname << " (" << ethercat::to_string(link.mac()) << "); process data of "
            << o.process_data << " (no drive model behind the boards: their inputs stay zero)"
            << std::endl;
  const auto start = std::chrono::steady_clock::now();
  uint64_t reported_malformed = 0;
  while (!stop) {
    const auto frame = link.receive(std::chrono::milliseconds(100));
    if (!frame) continue;
    const auto now = static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                               std::chrono::steady_clock::now() - start)
                                               .count());
    if (auto answer = ring.process(*frame, now)) link.send(*answer);
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
            << " datagrams), " << c.malformed << " dropped as malformed" << std::endl;
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
  app.add_flag("--eeprom-8-byte", o.eeprom_8_byte,
               "ESCs read 8 bytes of EEPROM per command (default 4)");
  cli.on_run(app, [&o] { return run(o); });
  return cli.run(argc, argv);
}
