#include "model_pipeline.hpp"

#include <Eigen/Core>
#include <stdexcept>

#include "concert/topology/scan_io.hpp"
#include "fuzz.hpp"

namespace concert::fuzz {

namespace {

void exercise_kinematics(const kinematics::Model& kin, const model::RobotModel& model) {
  kinematics::Data data = kin.make_data();
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
  double sum = 0.0;
  for (const std::string& frame : kin.frame_names())
    sum += kin.frame_pose(data, q, frame).translation().sum();
  for (const model::EndEffectorInfo& e : model.end_effectors()) {
    sum += kin.frame_jacobian(data, q, e.frame).sum();
  }
  sum += kin.gravity_torques(data, q).sum();
  volatile double sink = sum;
  (void)sink;
}

template <class F>
void documented(F&& f) {
  try {
    f();
  } catch (const model::ModelError&) {
  }
}

}  // namespace

const std::vector<Database>& databases() {
  static const std::vector<Database> dbs = [] {
    std::vector<Database> out;
    for (const auto& dir :
         {source_dir() / "data/module_db", shared_data_dir() / "concert_resources"}) {
      out.push_back({module_db::load_module_database(dir), topology::EscCatalog::load(dir)});
    }
    return out;
  }();
  return dbs;
}

const Database& database_of(const simbus::Assembly& assembly) {
  for (const Database& d : databases()) {
    if (d.catalog.find_key(assembly.modules.front().key) != nullptr) return d;
  }
  throw std::runtime_error(assembly.source + ": no module database knows its root module");
}

void exercise(const model::RobotModel& model) {
  for (const auto role : {model::ChainRole::kArm, model::ChainRole::kLeg, model::ChainRole::kTool,
                          model::ChainRole::kOther}) {
    for (const model::ChainInfo* c : model.chains(role))
      documented([&] { (void)model.chain(c->name); });
  }
  documented([&] { (void)model.arm(); });
  documented([&] { (void)model.legs(); });
  documented([&] { (void)model.tool(); });
  for (const auto kind : {model::EndEffectorKind::kDrill, model::EndEffectorKind::kGripper,
                          model::EndEffectorKind::kSanding, model::EndEffectorKind::kSpraying,
                          model::EndEffectorKind::kCamera, model::EndEffectorKind::kWheel,
                          model::EndEffectorKind::kOther}) {
    documented([&] { (void)model.tool(kind); });
    (void)model.end_effectors(kind);
  }
  for (const model::EndEffectorInfo& e : model.end_effectors()) {
    for (const auto kind :
         {model::SensorKind::kCamera, model::SensorKind::kLidar, model::SensorKind::kSonar,
          model::SensorKind::kImu, model::SensorKind::kForceTorque, model::SensorKind::kOther}) {
      documented([&] { (void)model.sensor(e, kind); });
      (void)model.sensor_frames(kind);
    }
  }
  exercise_kinematics(model.kinematics(), model);
  exercise_kinematics(model.planar_kinematics(), model);
}

void generate_with(const module_db::ModuleDatabase& db, const module_db::ModuleDescription& module,
                   const std::string& parent_key, const std::string& child_key) {
  module_db::ModuleDatabase with = db;
  with.add_module(module);
  const model_generation::ModelGenerator generator(with);

  topology::ModuleTree alone;
  alone.modules.push_back({.index = 0, .key = module.key, .slave_positions = {1}});
  topology::ModuleTree between;
  between.modules.push_back({.index = 0, .key = parent_key, .slave_positions = {1}});
  between.modules.push_back({.index = 1,
                             .key = module.key,
                             .slave_positions = {2},
                             .parent_module = 0,
                             .parent_connector = 1});
  between.modules.push_back({.index = 2,
                             .key = child_key,
                             .slave_positions = {3},
                             .parent_module = 1,
                             .parent_connector = 1});

  for (const topology::ModuleTree* tree : {&alone, &between}) generate_and_build(generator, *tree);
}

void module_file(std::string_view content, const std::string& name,
                 module_db::ModuleDescription (*load_module)(const std::filesystem::path&),
                 module_db::AddonDescription (*load_addon)(const std::filesystem::path&),
                 const module_db::ModuleDatabase& db, const std::string& parent_key,
                 const std::string& child_key) {
  const std::filesystem::path file = input_file(name, content);
  try {
    (void)load_addon(file);
  } catch (const module_db::ModuleDbError&) {
  }
  module_db::ModuleDescription module;
  try {
    module = load_module(file);
  } catch (const module_db::ModuleDbError&) {
    return;
  }
  if (db.find(module.key) != nullptr) return;  // a key of the database: refused when added
  generate_with(db, module, parent_key, child_key);
}

void generate_and_build(const model_generation::ModelGenerator& generator,
                        const topology::ModuleTree& tree) {
  model_generation::GeneratedModel generated;
  try {
    generated = generator.generate(tree);
  } catch (const model_generation::ModelError&) {
    return;
  }
  std::shared_ptr<const model::RobotModel> built;
  try {
    built = model::RobotModel::build(generated.description());
  } catch (const model::ModelError& e) {
    CONCERT_FUZZ_CHECK(false, std::string("modelgen generated a model the services refuse: ") +
                                  e.what() + "\nmodule tree:\n" + topology::tree_to_text(tree) +
                                  "URDF:\n" + generated.urdf);
  }
  exercise(*built);
}

}  // namespace concert::fuzz
