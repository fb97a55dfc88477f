// Module trees as JSON (libs/topology tree_from_json: `concert model generate --tree`, the shape
// `concert discover --json` prints) and what modelgen makes of any tree, as it does of the trees
// discovery publishes: a model generated with the project's and with the public database, which
// must build as the RobotModel the services read (model_pipeline.hpp). Documented failures:
// std::runtime_error from tree_from_json (naming the field), model_generation::ModelError.
//
// Seeds: the trees of the repository's assemblies, as `concert discover --json` prints them.
#include <filesystem>
#include <stdexcept>

#include "concert/model_generation/generator.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/scan_io.hpp"
#include "fuzz.hpp"
#include "model_pipeline.hpp"

using namespace concert;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(fuzz::text_of(data, size));
  } catch (const nlohmann::json::exception&) {
    return 0;  // `concert model generate`: "invalid JSON"
  }
  topology::ModuleTree tree;
  try {
    tree = topology::tree_from_json(doc, "tree.json");
  } catch (const std::runtime_error&) {
    return 0;
  }
  volatile size_t sink =
      topology::tree_to_text(tree).size() + topology::tree_to_json(tree).dump().size();
  (void)sink;
  for (const fuzz::Database& d : fuzz::databases()) {
    fuzz::generate_and_build(model_generation::ModelGenerator(d.db), tree);
  }
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  for (const std::filesystem::path& file : assembly_files()) {
    const simbus::Assembly assembly = simbus::load_assembly(file);
    const Database& d = database_of(assembly);
    seeds.add("tree_" + file.stem().string() + ".json",
              topology::tree_to_json(simbus::tree_from_assembly(assembly, d.catalog)).dump(1));
  }
  seeds.add_tokens(kJsonTokens);
}
