// concert_modelgen: subscribes to the module tree and customisation requests, publishes the
// versioned robot model (transient-local) and the service status.
//   concert_modelgen [--module-db DIR ...] [--bundle DIR] [--robot-name NAME]
// Without --module-db the project database (<source>/data/module_db) is used; several are
// merged in order. --bundle: also deploy every published model there (versions resume from it).
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/modelgen_node.hpp"

namespace {

struct Options {
  std::vector<std::string> module_dbs;
  std::string bundle;
  concert::modelgen::ServiceParams params;
};

int run(Options options) {
  using namespace concert;
  std::vector<std::filesystem::path> dbs(options.module_dbs.begin(), options.module_dbs.end());
  if (dbs.empty()) dbs.emplace_back(CONCERT_DEFAULT_MODULE_DB);
  if (!options.bundle.empty()) options.params.bundle_dir = options.bundle;
  const module_db::ModuleDatabase db = module_db::load_module_databases(dbs);
  modelgen::ModelgenService service(db, options.params);
  concert::dds::Participant participant({.name = "modelgen"});
  modelgen::dds::ModelgenNode node(participant, service, std::cout);
  const std::atomic<bool>& stop = cli::stop_on_signals();
  std::cout << "concert_modelgen: " << db.size() << " module descriptions, waiting for module trees on domain "
            << participant.domain_id() << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_modelgen",
                        "The model generation service: module tree -> robot model (URDF, SRDF, controller "
                        "configuration), versioned and latched.",
                        std::cout, std::cerr);
  Options options;
  CLI::App& app = cli.app();
  app.add_option("--module-db", options.module_dbs, "module database folder (repeat to merge; default: the project's)")
      ->type_name("DIR");
  app.add_option("--bundle", options.bundle,
                 "also deploy every published model to this folder (versions resume from it)")
      ->type_name("DIR");
  app.add_option("--robot-name", options.params.generator.robot_name, "name of the robot in the URDF")
      ->type_name("NAME")
      ->default_str(options.params.generator.robot_name);
  cli.on_run(app, [&options] { return run(options); });
  return cli.run(argc, argv);
}
