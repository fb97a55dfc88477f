// concert_modelgen: subscribes to the module tree and customisation requests, publishes the
// versioned robot model (transient-local) and the service status.
//   concert_modelgen [--module-db DIR ...] [--bundle DIR] [--robot-name NAME]
// Without --module-db the project database (<source>/data/module_db) is used; several are
// merged in order. --bundle: also deploy every published model there (versions resume from it).
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "concert/dds/participant.hpp"
#include "dds/modelgen_node.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop = true; }

constexpr const char* kUsage = "usage: concert_modelgen [--module-db DIR ...] [--bundle DIR] [--robot-name NAME]";

}  // namespace

int main(int argc, char** argv) {
  using namespace concert;
  std::vector<std::filesystem::path> dbs;
  modelgen::ServiceParams params;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage << "\n";
      return 0;
    }
    if (i + 1 >= argc) {
      std::cerr << "concert_modelgen: " << (arg.rfind("--", 0) == 0 ? "option " + arg + " needs a value" : "unknown argument '" + arg + "'")
                << "\n" << kUsage << "\n";
      return 2;
    }
    const std::string value = argv[++i];
    if (arg == "--module-db") {
      dbs.emplace_back(value);
    } else if (arg == "--bundle") {
      params.bundle_dir = value;
    } else if (arg == "--robot-name") {
      params.generator.robot_name = value;
    } else {
      std::cerr << "concert_modelgen: unknown argument '" << arg << "'\n" << kUsage << "\n";
      return 2;
    }
  }
  if (dbs.empty()) dbs.emplace_back(CONCERT_DEFAULT_MODULE_DB);
  try {
    const module_db::ModuleDatabase db = module_db::load_module_databases(dbs);
    modelgen::ModelgenService service(db, params);
    concert::dds::Participant participant({.name = "modelgen"});
    modelgen::dds::ModelgenNode node(participant, service, std::cout);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::cout << "concert_modelgen: " << db.size() << " module descriptions, waiting for module trees on domain "
              << participant.domain_id() << std::endl;
    node.spin(g_stop);
  } catch (const std::exception& e) {
    std::cerr << "concert_modelgen: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
