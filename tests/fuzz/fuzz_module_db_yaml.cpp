// Module and add-on files of the project's YAML module database (libs/module_db, schema in
// data/module_db/README.md), and what modelgen makes of a module: it is generated alone and
// between real modules of the project database (model_pipeline.hpp). Documented failures:
// ModuleDbError, model_generation::ModelError; a generated model must build as a RobotModel.
#include "concert/module_db/module_db.hpp"
#include "fuzz.hpp"
#include "model_pipeline.hpp"

using namespace concert;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::module_file(fuzz::text_of(data, size), "fuzz_module.yaml", module_db::load_yaml_module,
                    module_db::load_yaml_addon, fuzz::databases()[0].db, "concert_elbow_a",
                    "concert_drill");
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add_files(source_dir() / "data/module_db/modules", ".yaml");
  seeds.add_files(source_dir() / "data/module_db/addons", ".yaml");
  seeds.add_tokens(kYamlTokens);
}
