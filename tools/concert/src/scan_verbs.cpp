#include "scan_verbs.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/ethercat/esc.hpp"
#include "concert/ethercat/cyclic.hpp"
#include "concert/ethercat/drive_pdo.hpp"
#include "concert/ethercat/master.hpp"
#include "concert/cli/stop_signals.hpp"
#include <pthread.h>
#include <sched.h>
#include <cstring>
#include "concert/simbus/assembly.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "concert/topology/scan_io.hpp"

namespace concert::tool {

topology::EscCatalog load_catalogs(std::vector<std::string> module_dbs) {
  if (module_dbs.empty()) module_dbs.push_back(CONCERT_DEFAULT_MODULE_DB);
  auto catalog = topology::EscCatalog::load(module_dbs.front());
  for (size_t i = 1; i < module_dbs.size(); ++i) catalog.merge(topology::EscCatalog::load(module_dbs[i]));
  return catalog;
}

namespace {

/// Where a scan comes from: a scan file, or the scan an assembly gives on the simulated bus
/// (with the module databases' ESC catalogue).
struct ScanSource {
  std::string scan_file;
  std::string assembly_file;
  std::vector<std::string> module_dbs;

  topology::EscScan load() const {
    if (!scan_file.empty()) return topology::load_scan(scan_file);
    return simbus::simulate_scan(simbus::load_assembly(assembly_file), load_catalogs(module_dbs));
  }
};

void add_source_options(CLI::App& verb, ScanSource& source) {
  CLI::Option* scan =
      verb.add_option("--scan", source.scan_file, "a scan file (YAML or JSON)")->type_name("FILE");
  CLI::Option* assembly = verb.add_option("--assembly", source.assembly_file,
                                          "an assembly file, scanned on the simulated bus")
                              ->type_name("FILE");
  scan->excludes(assembly);
  verb.add_option("--module-db", source.module_dbs,
                  "module database folder (repeat to merge; default: the project's)")
      ->type_name("DIR");
  verb.callback([scan, assembly] {
    if (scan->count() + assembly->count() != 1) {
      throw CLI::ValidationError("give exactly one of --scan FILE or --assembly FILE");
    }
  });
}

struct PublishOptions {
  ScanSource source;
  double hold_s = 0.0;
  uint32_t scan_id = 1;
  std::string name = "concert-scan";
  cli::DdsOptions dds;
};

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

int publish(const PublishOptions& o, std::ostream& out, std::ostream& err) {
  const auto scan = o.source.load();
  const int32_t domain = o.dds.domain_id();
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  dds::Participant participant({.name = "concert-scan", .domain_id = domain});
  dds::Writer<msg::EscScan> writer(participant, dds::topics::esc_scan);
  // --timeout: wait (bounded) for a reader, e.g. the discovery service, before publishing.
  if (o.dds.timeout_s > 0 && !writer.wait_for_readers(1, o.dds.timeout())) {
    err << "concert scan publish: no reader of the scan within " << o.dds.timeout_s
        << " s; publishing anyway\n";
  }
  writer.write(topology::dds::to_msg(scan, o.scan_id, now_ns(), o.name));
  if (o.dds.json) out << topology::scan_to_json(scan).dump() << std::endl;
  err << "concert scan publish: published " << scan.slaves.size() << " slaves as scan " << o.scan_id
      << " on domain " << domain
      << (o.hold_s > 0 ? "; holding it for late joiners" : "; holding it until Ctrl-C")
      << std::endl;
  // The scan is latched: it stays available to late joiners while this writer lives.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.hold_s);
  while (!g_stop && (o.hold_s == 0 || std::chrono::steady_clock::now() < deadline)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return 0;
}

struct ReadOptions {
  std::string ifname;
  bool json = false;
  bool details = false;
  double frame_timeout_ms = 20;
  int tries = 3;
};

std::string hex(uint32_t value, int digits) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%0*X", digits, value);
  return text;
}

/// `concert scan read`: the scan the master reads on a network interface, in the format of
/// `concert scan show`; a summary (and with --details every register read) on stderr.
int read_scan(const ReadOptions& o, std::ostream& out, std::ostream& err) {
  ethercat::RawSocketLink link(o.ifname);
  ethercat::MasterParams params;
  params.frame_timeout =
      std::chrono::microseconds(static_cast<int64_t>(o.frame_timeout_ms * 1000.0));
  params.tries = o.tries;
  ethercat::Master master(link, params);
  const auto start = std::chrono::steady_clock::now();
  const ethercat::ScanReport report = master.scan();
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const topology::EscScan scan = report.scan();
  if (o.json) {
    out << topology::scan_to_json(scan).dump(2) << "\n";
  } else {
    out << topology::scan_to_yaml(scan);
  }
  char timing[64];
  std::snprintf(timing, sizeof timing, "%.1f ms", ms);
  err << "concert scan read: " << report.slaves.size() << " slaves on " << o.ifname << " in "
      << timing << " (" << report.frames_sent << " frames, " << report.frames_lost << " lost)\n";
  if (o.details) {
    for (const auto& s : report.slaves) {
      err << "  slave " << s.position << ": station " << hex(s.station_address, 4) << ", chip "
          << hex(s.chip_type, 2) << " rev " << int(s.chip_revision) << ", ports "
          << hex(s.port_descriptor, 2) << ", DL status " << hex(s.dl_status, 4) << ", AL "
          << ethercat::esc::to_string(static_cast<ethercat::esc::AlState>(s.al_status & 0x0F))
          << ((s.al_status & ethercat::esc::kAlErrorBit)
                  ? " error " + hex(s.al_status_code, 4) + " (" +
                        ethercat::esc::al_status_code_name(s.al_status_code) + ")"
                  : std::string())
          << ", vendor " << hex(s.sii.vendor_id, 8) << ", product " << s.sii.product_code
          << ", serial " << s.sii.serial << ", DC receive times";
      for (const uint32_t t : s.receive_time) err << " " << t;
      err << "\n";
    }
  }
  return 0;
}

struct CycleOptions {
  std::string ifname;
  int lost_in_a_row = 3;
  double frame_timeout_ms = 20;
  int tries = 3;
  double cycle_timeout_us = 0;  // 0: one period
  bool feedback = false;
  std::string process_data = CONCERT_DEFAULT_PROCESS_DATA;
  double seconds = 1.0;
  int period_us = 1000;
  int fifo = 0;
  bool json = false;
};

/// `concert ethercat cycle`: the ring to OP, cyclic process data for a while, back to INIT.
int cycle_ring(const CycleOptions& o, std::ostream& out, std::ostream& err) {
  const std::atomic<bool>& stop = cli::stop_on_signals();
  ethercat::RawSocketLink link(o.ifname);
  ethercat::MasterParams mp;
  mp.frame_timeout = std::chrono::microseconds(static_cast<int64_t>(o.frame_timeout_ms * 1000.0));
  mp.tries = o.tries;
  mp.cycle_timeout = std::chrono::microseconds(
      static_cast<int64_t>(o.cycle_timeout_us > 0 ? o.cycle_timeout_us : o.period_us));
  ethercat::Master master(link, mp);
  const ethercat::ScanReport report = master.scan();
  if (report.slaves.empty()) throw cli::Failure("no slave answers on " + o.ifname);
  // However this ends (a watchdog fault, an error, Ctrl-C), the ring is asked back to INIT.
  struct BackToInit {
    ethercat::Master& master;
    const ethercat::ScanReport& report;
    ~BackToInit() {
      try {
        master.request_state(report, ethercat::esc::AlState::kInit);
      } catch (const std::exception&) {
        // The ring may be gone (a pulled cable): nothing more to ask.
      }
    }
  } back_to_init{master, report};
  ethercat::ProcessImage image = master.map_process_data(report);
  for (const auto state : {ethercat::esc::AlState::kPreOp, ethercat::esc::AlState::kSafeOp}) {
    master.request_state(report, state);
  }
  // Outputs flow before OP is asked for, as drives expect valid outputs on entering OP.
  for (int i = 0; i < 10; ++i) master.cycle(image);
  master.request_state(report, ethercat::esc::AlState::kOp);
  std::string scheduling = "SCHED_OTHER";
  if (o.fifo > 0) {
    sched_param p{};
    p.sched_priority = o.fifo;
    const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
    if (rc == 0) {
      scheduling = "SCHED_FIFO " + std::to_string(o.fifo);
    } else {
      err << "concert ethercat cycle: --fifo " << o.fifo << " not applied (" << std::strerror(rc)
          << "); running SCHED_OTHER\n";
    }
  }
  err << "concert ethercat cycle: " << report.slaves.size() << " slaves in OP on " << o.ifname
      << ", " << image.slaves.size() << " with process data (" << image.outputs.size()
      << " bytes out, " << image.inputs.size() << " in), " << o.period_us << " us period, "
      << scheduling << ", " << o.seconds << " s\n";
  ethercat::CycleParams params;
  params.period = std::chrono::microseconds(o.period_us);
  params.duration = std::chrono::nanoseconds(static_cast<int64_t>(o.seconds * 1e9));
  // The cycle watchdog: a frame back with a working counter short of the expected one, or
  // --lost-in-a-row frames lost in a row, ends the run; the master then says what changed.
  std::string fault;
  uint64_t cycle_number = 0;
  int lost_in_a_row = 0;
  const ethercat::CycleBody watch = [&](ethercat::ProcessImage&, const ethercat::CycleResult& r) {
    ++cycle_number;
    lost_in_a_row = r.returned ? 0 : lost_in_a_row + 1;
    if (r.returned && r.wkc != image.expected_wkc) {
      fault = "cycle " + std::to_string(cycle_number) + ": working counter " + std::to_string(r.wkc) +
              " of " + std::to_string(image.expected_wkc);
    } else if (o.lost_in_a_row > 0 && lost_in_a_row == o.lost_in_a_row) {
      fault = "cycle " + std::to_string(cycle_number) + ": " + std::to_string(lost_in_a_row) + " frames lost in a row";
    }
    return fault.empty();
  };
  const ethercat::CycleStats stats = ethercat::run_cycles(master, image, params, stop, watch);
  if (!fault.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    const ethercat::RingDiagnosis d = master.diagnose(report);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    char took[32];
    std::snprintf(took, sizeof took, "%.1f ms", ms);
    err << "concert ethercat cycle: " << fault << ": " << d.text() << " (diagnosed in " << took << ")\n";
    out << stats.summary() << "\n";
    throw cli::Failure("the ring stopped exchanging as mapped: " + d.text());
  }
  if (o.feedback) {
    // Each drive board's last inputs, decoded with the process data file.
    const auto catalog = ethercat::ProcessDataCatalog::load(o.process_data);
    for (const auto& m : image.slaves) {
      const auto& s = report.slaves[static_cast<std::size_t>(m.position - 1)];
      const ethercat::BoardProcessData* board = catalog.find(s.slave.esc_type);
      if (!board || !board->input("link_position")) continue;
      if (board->input_bytes() > m.input_bytes) {
        err << "  slave " << m.position << ": its SII gives " << m.input_bytes << " bytes of inputs, "
            << o.process_data << " a drive " << board->input_bytes() << "\n";
        continue;
      }
      const ethercat::DriveFeedback f = ethercat::DriveCodec(*board).decode_feedback(
          std::span<const uint8_t>(image.inputs).subspan(m.input_offset, m.input_bytes));
      char line[200];
      std::snprintf(line, sizeof line,
                    "  slave %d robot_id %d: status 0x%04X fault 0x%04X position %+.4f rad velocity %+.4f rad/s torque %+.3f N m\n",
                    m.position, s.sii.robot_id, f.status_word, f.fault, f.link_position, f.velocity, f.torque);
      err << line;
    }
  }
  if (o.json) {
    nlohmann::json j = {{"slaves", report.slaves.size()},
                        {"process_data_slaves", image.slaves.size()},
                        {"period_us", o.period_us},
                        {"cycles", stats.cycles},
                        {"lost", stats.lost},
                        {"short_wkc", stats.short_wkc},
                        {"expected_wkc", stats.expected_wkc},
                        {"period_mean_us", stats.period_mean_us},
                        {"period_p50_us", stats.period_p50_us},
                        {"period_p99_us", stats.period_p99_us},
                        {"period_max_us", stats.period_max_us},
                        {"jitter_p99_us", stats.jitter_p99_us},
                        {"cpu_per_cycle_us", stats.cpu_per_cycle_us},
                        {"scheduling", scheduling}};
    out << j.dump(2) << "\n";
  } else {
    out << stats.summary() << "\n";
  }
  return 0;
}

}  // namespace

void register_scan_verbs(cli::Cli& concert) {
  CLI::App& scan = concert.group(concert.app(), "scan",
                                 "EtherCAT scans: show one, read one off a ring, or publish one as a master would");

  struct ShowOptions {
    ScanSource source;
    bool json = false;
  };
  auto show_options = std::make_shared<ShowOptions>();
  CLI::App& show =
      concert.verb(scan, "show", "the scan an assembly gives on the simulated bus (or a scan file)",
                   [&concert, show_options] {
                     const auto s = show_options->source.load();
                     if (show_options->json) {
                       concert.out() << topology::scan_to_json(s).dump(2) << "\n";
                     } else {
                       concert.out() << topology::scan_to_yaml(s);
                     }
                     return 0;
                   });
  add_source_options(show, show_options->source);
  show.add_flag("--json", show_options->json, "JSON instead of YAML");

  auto r = std::make_shared<ReadOptions>();
  CLI::App& read = concert.verb(
      scan, "read",
      "bring an EtherCAT ring up to INIT on a network interface and print its scan (as show "
      "does; needs root or CAP_NET_RAW)",
      [&concert, r] { return read_scan(*r, concert.out(), concert.err()); });
  read.add_option("--ifname", r->ifname, "network interface of the EtherCAT ring")
      ->type_name("IF")
      ->required();
  read.add_flag("--json", r->json, "JSON instead of YAML");
  read.add_flag("--details", r->details,
                "also print every slave's station address, ESC, DL and AL status, SII identity "
                "and DC receive times (stderr)");
  read.add_option("--frame-timeout", r->frame_timeout_ms,
                  "milliseconds to wait for a frame to come back before resending it")
      ->type_name("MS")
      ->check(cli::number(0, 10000, false, true))
      ->capture_default_str();
  read.add_option("--tries", r->tries, "sends of a frame before the read fails")
      ->type_name("N")
      ->check(cli::number(1, 100, true))
      ->capture_default_str();

  CLI::App& ecat = concert.group(concert.app(), "ethercat",
                                 "the EtherCAT master on a network interface (root or CAP_NET_RAW)");
  auto c = std::make_shared<CycleOptions>();
  CLI::App& cyc = concert.verb(
      ecat, "cycle",
      "bring the ring on an interface to OP, exchange process data every period for a while "
      "(one LRW a cycle), report period, jitter, lost frames and CPU, return it to INIT",
      [&concert, c] { return cycle_ring(*c, concert.out(), concert.err()); });
  cyc.add_option("--ifname", c->ifname, "network interface of the EtherCAT ring")
      ->type_name("IF")
      ->required();
  cyc.add_option("--seconds", c->seconds, "how long to cycle")
      ->type_name("S")
      ->check(cli::number(0, 86400, false, true))
      ->capture_default_str();
  cyc.add_option("--period-us", c->period_us, "cycle period in microseconds")
      ->type_name("US")
      ->check(cli::number(100, 1000000, true))
      ->capture_default_str();
  cyc.add_option("--fifo", c->fifo, "run the cycle thread SCHED_FIFO at this priority (0: no)")
      ->type_name("PRIO")
      ->check(cli::number(0, 99, true));
  cyc.add_flag("--json", c->json, "the figures as JSON");
  cyc.add_option("--frame-timeout", c->frame_timeout_ms,
                 "bring-up: milliseconds to wait for a frame before resending it")
      ->type_name("MS")
      ->check(cli::number(0, 10000, false, true))
      ->capture_default_str();
  cyc.add_option("--tries", c->tries, "bring-up: sends of a frame before it fails")
      ->type_name("N")
      ->check(cli::number(1, 100, true))
      ->capture_default_str();
  cyc.add_option("--cycle-timeout", c->cycle_timeout_us,
                 "microseconds a cycle's frame may take before the cycle counts as lost (default: one period)")
      ->type_name("US")
      ->check(cli::number(0, 1e6, false));
  cyc.add_option("--lost-in-a-row", c->lost_in_a_row,
                 "frames lost in a row that end the run (0: count them, never stop)")
      ->type_name("N")
      ->check(cli::number(0, 1e6, true))
      ->capture_default_str();
  cyc.add_flag("--feedback", c->feedback, "print every drive board's last feedback (stderr)");
  cyc.add_option("--process-data", c->process_data, "process data of each board type (for --feedback)")
      ->type_name("FILE")
      ->capture_default_str();

  auto o = std::make_shared<PublishOptions>();
  CLI::App& pub =
      concert.verb(scan, "publish", "publish a scan as an EtherCAT master would (latched)",
                   [&concert, o] { return publish(*o, concert.out(), concert.err()); });
  add_source_options(pub, o->source);
  cli::Cli::add_seconds_option(
      pub, "--hold", "--hold-ms", o->hold_s,
      "keep the latched scan for late joiners this long (0: until Ctrl-C)");
  pub.add_option("--scan-id", o->scan_id, "the scan's id")
      ->type_name("N")
      ->check(cli::number(1, 4e9, true));
  pub.add_option("--source", o->name, "the scan's source name")->type_name("NAME");
  concert.add_dds_options(
      pub, o->dds, 0.0,
      "wait up to S seconds for a reader of the scan before publishing (0: do not wait)");
}

}  // namespace concert::tool
