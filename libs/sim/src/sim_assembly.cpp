#include "concert/sim/sim_assembly.hpp"

#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "concert/kinematics/model.hpp"
#include "concert/mobile_base/base_kinematics.hpp"
#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::sim {
namespace {

/// The bits of the drill end-effectors: the TCP link, and the diameter from a "drillbit_<mm>_..."
/// add-on when one is mounted (the public database's keys, e.g. drillbit_12_SDSmax), else 12 mm.
std::vector<DrillBit> drill_bits(const std::vector<model_generation::EndEffectorInfo>& end_effectors) {
  static const std::regex kBit(R"(^drillbit_([0-9]+)_)");
  std::vector<DrillBit> bits;
  for (const auto& ee : end_effectors) {
    if (ee.kind != model::EndEffectorKind::kDrill) continue;
    DrillBit bit{ee.frame, 0.012};
    for (const std::string& addon : ee.addons) {
      std::smatch m;
      if (std::regex_search(addon, m, kBit)) bit.diameter = 1e-3 * std::stod(m[1].str());
    }
    bits.push_back(bit);
  }
  return bits;
}

/// The links moved with the sanding end-effectors: the subtree of the last movable joint above
/// each one's TCP link.
std::vector<std::string> sanding_links(
    const std::string& urdf, const std::vector<model_generation::EndEffectorInfo>& end_effectors) {
  std::vector<std::string> links;
  bool any = false;
  for (const auto& ee : end_effectors) any = any || ee.kind == model::EndEffectorKind::kSanding;
  if (!any) return links;
  const kinematics::Model k = kinematics::Model::from_urdf_string(urdf);
  for (const auto& ee : end_effectors) {
    if (ee.kind != model::EndEffectorKind::kSanding) continue;
    int last = -1;
    std::size_t smallest = 0;
    for (int j = 0; j < k.dof(); ++j) {
      const std::vector<std::string> sub = k.subtree_links(j);
      if (std::find(sub.begin(), sub.end(), ee.frame) == sub.end()) continue;
      if (last < 0 || sub.size() < smallest) {
        last = j;
        smallest = sub.size();
      }
    }
    if (last < 0) continue;  // a sanding tool on the root: nothing moves it
    for (const std::string& l : k.subtree_links(last)) {
      if (std::find(links.begin(), links.end(), l) == links.end()) links.push_back(l);
    }
  }
  return links;
}

/// The steering legs of the generated model, by role (mobile_base::steering_legs).
std::vector<SimLeg> steering_legs(const model_generation::GeneratedModel& generated) {
  std::vector<SimLeg> legs;
  for (const mobile_base::Leg& leg : mobile_base::steering_legs(*model::RobotModel::build(generated.description()))) {
    legs.push_back({leg.steering_joint, leg.wheel_joint, leg.wheel_radius});
  }
  return legs;
}

/// Who a module is across hot swaps: its key and robot_id (the one its upstream ESC reports),
/// else (no robot_id) its key and the connectors from the root down to it.
std::string module_identity(const topology::ModuleTree& tree, int index) {
  const topology::ModuleNode& node = tree.modules.at(static_cast<std::size_t>(index));
  if (node.robot_id >= 0) return node.key + " robot_id " + std::to_string(node.robot_id);
  std::string place;
  for (int m = index; m >= 0; m = tree.modules.at(static_cast<std::size_t>(m)).parent_module) {
    place = "/" + std::to_string(tree.modules.at(static_cast<std::size_t>(m)).parent_connector) + place;
  }
  return node.key + " at " + place;
}

}  // namespace

std::vector<SensorMount> sensor_mounts(const std::vector<model::SensorFrame>& frames) {
  std::vector<SensorMount> out;
  for (const model::SensorFrame& f : frames) {
    switch (f.kind) {
      case model::SensorKind::kCamera:
        out.push_back({f.name, hardware::SensorType::kRgbd, f.frame});
        break;
      case model::SensorKind::kLidar:
        out.push_back({f.name, hardware::SensorType::kLidar, f.frame});
        break;
      case model::SensorKind::kSonar:
        out.push_back({f.name, hardware::SensorType::kSonar, f.frame});
        break;
      case model::SensorKind::kImu:
        out.push_back({f.name, hardware::SensorType::kImu, f.frame});
        break;
      case model::SensorKind::kForceTorque:
      case model::SensorKind::kOther:
        break;
    }
  }
  return out;
}

struct AssemblyBuilder::Impl {
  module_db::ModuleDatabase db;
  topology::EscCatalog catalog;
  std::unique_ptr<model_generation::ModelGenerator> generator;  // points into db: Impl never moves
};

AssemblyBuilder::AssemblyBuilder(const std::vector<std::filesystem::path>& module_db_dirs)
    : impl_(std::make_unique<Impl>()) {
  if (module_db_dirs.empty()) {
    throw std::runtime_error("sim assembly: no module database folder given");
  }
  impl_->db = module_db::load_module_databases(module_db_dirs);
  impl_->catalog = topology::EscCatalog::load(module_db_dirs.front());
  for (std::size_t i = 1; i < module_db_dirs.size(); ++i) {
    impl_->catalog.merge(topology::EscCatalog::load(module_db_dirs[i]));
  }
  impl_->generator = std::make_unique<model_generation::ModelGenerator>(impl_->db);
}

AssemblyBuilder::~AssemblyBuilder() = default;
AssemblyBuilder::AssemblyBuilder(AssemblyBuilder&&) noexcept = default;
AssemblyBuilder& AssemblyBuilder::operator=(AssemblyBuilder&&) noexcept = default;

SimulatedRobot AssemblyBuilder::build(const std::filesystem::path& assembly_file) const {
  std::ifstream in(assembly_file);
  if (!in) {
    throw std::runtime_error("cannot open assembly file '" + assembly_file.string() + "'");
  }
  std::stringstream text;
  text << in.rdbuf();
  return build_from_text(text.str(), assembly_file.string());
}

SimulatedRobot AssemblyBuilder::build_from_text(const std::string& yaml, const std::string& source) const {
  const simbus::Assembly assembly = simbus::parse_assembly(yaml, source);
  simbus::validate(assembly, impl_->catalog);
  SimulatedRobot out;
  out.source = source;
  out.scan = simbus::simulate_scan(assembly, impl_->catalog);
  out.tree = simbus::tree_from_assembly(assembly, impl_->catalog);
  try {
    const model_generation::GeneratedModel model = impl_->generator->generate(out.tree);
    out.urdf = model.urdf;
    out.sensors = sensor_mounts(model.sensor_frames);
    out.drill_bits = drill_bits(model.end_effectors);
    out.sanding_links = sanding_links(model.urdf, model.end_effectors);
    for (const auto& ee : model.end_effectors) {
      if (ee.kind == model::EndEffectorKind::kGripper) out.gripper_tcps.push_back(ee.frame);
    }
    out.legs = steering_legs(model);
    std::map<int, int> joints_of_module;  // a module's moving joints so far (model order)
    for (const model_generation::JointInfo& j : model.joints) {
      if (j.module >= 0) {
        const int n = joints_of_module[j.module]++;
        out.joint_modules[j.name] =
            module_identity(out.tree, j.module) + (n > 0 ? " joint " + std::to_string(n + 1) : std::string());
        out.joint_robot_ids[j.name] = out.tree.modules.at(static_cast<std::size_t>(j.module)).robot_id;
      }
      out.joint_homes[j.name] = j.home;
    }
  } catch (const std::exception& e) {
    throw std::runtime_error("assembly '" + source + "': model generation failed: " + e.what());
  }
  return out;
}

}  // namespace concert::sim
