// concert_discovery: subscribes to the EtherCAT scan, publishes the module tree (versioned,
// transient-local) and the service status.
//   concert_discovery [--module-db DIR ...] [--port-order 0312|0123] [--params FILE]
// --params: config/discovery.yaml lists every key with its default (flags override it).
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <iostream>
#include <string>
#include <vector>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/discovery_node.hpp"
#include "dds/service_params.hpp"
#include "concert/topology/reconstruction.hpp"

namespace {

struct Options {
  std::vector<std::string> module_dbs;
  std::string port_order;
  std::string params;
};

int run(const Options& options) {
  using namespace concert;
  discovery::dds::ServiceParams settings;
  if (!options.params.empty()) settings = discovery::dds::load_service_params(options.params);
  if (!options.module_dbs.empty()) settings.module_dbs = options.module_dbs;
  if (!options.port_order.empty()) settings.port_order = options.port_order;
  if (settings.module_dbs.empty()) settings.module_dbs.push_back(CONCERT_DEFAULT_MODULE_DB);
  const topology::PortOrder order = *topology::parse_port_order(settings.port_order);
  topology::EscCatalog catalog;
  for (const auto& db : settings.module_dbs) catalog.merge(topology::EscCatalog::load(db));
  const std::size_t entries = catalog.entries().size();

  const std::atomic<bool>& stop = cli::stop_on_signals();
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "discovery"});
  discovery::dds::DiscoveryNode node(participant,
                                     discovery::DiscoveryService(topology::Discovery(
                                         std::move(catalog), topology::DiscoveryParams{order})),
                                     std::cerr);
  std::cerr << "concert_discovery: " << entries << " catalogue entries from "
            << settings.module_dbs.size() << " database(s), port order " << settings.port_order
            << ", domain " << participant.domain_id() << "\n";
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_discovery",
                        "The discovery service: EtherCAT scan -> module tree (versioned, latched).",
                        std::cout, std::cerr);
  Options options;
  CLI::App& app = cli.app();
  app.add_option("--module-db", options.module_dbs,
                 "module database folder (repeat to merge; default: the project's)")
      ->type_name("DIR");
  concert::cli::Cli::add_choice(app, "--port-order", options.port_order, {"0312", "0123"},
                                "frame processing order of the ESC ports");
  app.add_option("--params", options.params, "parameters file (config/discovery.yaml)")
      ->type_name("FILE");
  cli.on_run(app, [&options] { return run(options); });
  return cli.run(argc, argv);
}
