// concert_discovery: subscribes to the EtherCAT scan, publishes the module tree (versioned,
// transient-local) and the service status.
//   concert_discovery [--module-db DIR ...] [--port-order 0312|0123] [--params FILE]
// --params: YAML with `module_db: [DIR, ...]` and `port_order: "0312"` (flags override).
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "concert/dds/participant.hpp"
#include "dds/discovery_node.hpp"
#include "discovery/discovery.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop = true; }

constexpr const char* kUsage =
    "usage: concert_discovery [--module-db DIR ...] [--port-order 0312|0123] [--params FILE]";

struct Settings {
  std::vector<std::string> module_dbs;
  std::string port_order = "0312";
};

void load_params(const std::string& file, Settings& settings) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(file + ": " + e.what());
  }
  if (!root.IsMap()) throw std::runtime_error(file + ": expected a mapping");
  if (const auto dbs = root["module_db"]) {
    if (dbs.IsScalar()) {
      settings.module_dbs.push_back(dbs.Scalar());
    } else if (dbs.IsSequence()) {
      for (const auto& db : dbs) {
        if (!db.IsScalar()) throw std::runtime_error(file + ": module_db: expected folder names");
        settings.module_dbs.push_back(db.Scalar());
      }
    } else {
      throw std::runtime_error(file + ": module_db: expected a folder or a list of folders");
    }
  }
  if (const auto order = root["port_order"]) {
    if (!order.IsScalar()) throw std::runtime_error(file + ": port_order: expected 0312 or 0123");
    settings.port_order = order.Scalar();
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace concert;
  Settings settings;
  std::vector<std::string> flag_dbs;
  std::string flag_order;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::runtime_error("option " + arg + " needs a value");
        return argv[++i];
      };
      if (arg == "--module-db") {
        flag_dbs.push_back(value());
      } else if (arg == "--port-order") {
        flag_order = value();
      } else if (arg == "--params") {
        load_params(value(), settings);
      } else if (arg == "--help" || arg == "-h") {
        std::cout << kUsage << "\n";
        return 0;
      } else {
        throw std::runtime_error("unknown argument '" + arg + "'");
      }
    }
    if (!flag_dbs.empty()) settings.module_dbs = flag_dbs;
    if (!flag_order.empty()) settings.port_order = flag_order;
    if (settings.module_dbs.empty()) settings.module_dbs.push_back(CONCERT_DEFAULT_MODULE_DB);
    const auto order = topology::parse_port_order(settings.port_order);
    if (!order) {
      throw std::runtime_error("port order '" + settings.port_order +
                               "': expected 0312 or 0123");
    }
    topology::EscCatalog catalog;
    for (const auto& db : settings.module_dbs) catalog.merge(topology::EscCatalog::load(db));
    const std::size_t entries = catalog.entries().size();

    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "discovery"});
    discovery::dds::DiscoveryNode node(
        participant,
        discovery::DiscoveryService(discovery::Discovery(std::move(catalog),
                                                          discovery::Params{*order})),
        std::cerr);
    std::cerr << "concert_discovery: " << entries
              << " catalogue entries from " << settings.module_dbs.size()
              << " database(s), port order " << settings.port_order << ", domain "
              << participant.domain_id() << "\n";
    node.spin(g_stop);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "concert_discovery: " << e.what() << "\n" << kUsage << "\n";
    return 1;
  }
}
