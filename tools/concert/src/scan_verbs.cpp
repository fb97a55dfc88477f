#include "scan_verbs.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "args.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "concert/topology/scan_io.hpp"

namespace concert::cli {
namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

}  // namespace

topology::EscCatalog load_catalogs(std::vector<std::string> module_dbs) {
  if (module_dbs.empty()) module_dbs.push_back(CONCERT_DEFAULT_MODULE_DB);
  auto catalog = topology::EscCatalog::load(module_dbs.front());
  for (size_t i = 1; i < module_dbs.size(); ++i) catalog.merge(topology::EscCatalog::load(module_dbs[i]));
  return catalog;
}

namespace {

/// The scan named on the command line: a scan file, or the scan an assembly gives on the
/// simulated bus (with the module databases' ESC catalogue).
topology::EscScan scan_from(Args& a) {
  const auto scan_file = a.value("--scan");
  const auto assembly_file = a.value("--assembly");
  auto dbs = a.values("--module-db");
  if (scan_file.has_value() == assembly_file.has_value()) {
    throw UsageError("give exactly one of --scan FILE or --assembly FILE");
  }
  if (scan_file) return topology::load_scan(*scan_file);
  return simbus::simulate_scan(simbus::load_assembly(*assembly_file), load_catalogs(dbs));
}

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int run_scan(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  Args a(args);
  const std::string verb = a.positional("scan verb: show or publish");
  if (verb == "show") {
    const bool json = a.flag("--json");
    const auto scan = scan_from(a);
    a.finish();
    if (json) {
      out << topology::scan_to_json(scan).dump(2) << "\n";
    } else {
      out << topology::scan_to_yaml(scan);
    }
    return 0;
  }
  if (verb != "publish") throw UsageError("unknown scan verb '" + verb + "' (show, publish)");

  const auto domain_arg = a.value("--domain");
  const long hold_ms = a.integer("--hold-ms", 0, 0, 86'400'000);
  const long scan_id = a.integer("--scan-id", 1, 1, 4'000'000'000);
  const std::string source = a.value("--source").value_or("concert-scan");
  const auto scan = scan_from(a);
  a.finish();
  const int32_t domain = domain_arg ? dds::parse_domain_id(*domain_arg, "--domain") : dds::domain_id_from_env();

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  dds::Participant participant({.name = "concert-scan", .domain_id = domain});
  dds::Writer<msg::EscScan> writer(participant, dds::topics::esc_scan);
  writer.write(topology::dds::to_msg(scan, static_cast<uint32_t>(scan_id), now_ns(), source));
  err << "concert scan publish: published " << scan.slaves.size() << " slaves as scan " << scan_id << " on domain "
      << domain << (hold_ms ? "; holding it for late joiners" : "; holding it until Ctrl-C") << std::endl;
  // The scan is latched: it stays available to late joiners while this writer lives.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(hold_ms);
  while (!g_stop && (hold_ms == 0 || std::chrono::steady_clock::now() < deadline)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return 0;
}

}  // namespace concert::cli
