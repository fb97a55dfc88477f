// Module and add-on files of the public CoBRA/Timor JSON module database (libs/module_db), and
// what modelgen makes of a module: it is generated alone and between real modules of the public
// database (model_pipeline.hpp). Documented failures: ModuleDbError,
// model_generation::ModelError; a generated model must build as a RobotModel.
#include "concert/module_db/module_db.hpp"
#include "fuzz.hpp"
#include "model_pipeline.hpp"

using namespace concert;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::module_file(fuzz::text_of(data, size), "fuzz_module.json", module_db::load_json_module,
                    module_db::load_json_addon, fuzz::databases()[1].db,
                    "module_joint_elbow_A_concert", "module_drill_concert");
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add_files(shared_data_dir() / "concert_resources/json", ".json");
  seeds.add_files(shared_data_dir() / "concert_resources/module_addons/json", ".json");
  seeds.add_tokens(kJsonTokens);
}
