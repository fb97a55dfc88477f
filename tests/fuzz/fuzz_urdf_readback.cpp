// The robot model as every service reads it back from the RobotModel message
// (libs/model RobotModel::build: URDF through urdfdom and KDL, the SRDF's disabled pairs, the
// description's tables checked against the URDF), then what the services ask of it first
// (model_pipeline.hpp exercise()). Documented failure: model::ModelError.
//
// Input: URDF text, NUL, SRDF text, NUL, the description's tables, one record a line:
//   joint NAME CHAIN LOWER UPPER VELOCITY PEAK CONTINUOUS
//   chain NAME ROLE BASE_LINK TIP_LINK [JOINT...]
//   ee NAME CHAIN FRAME MODULE KIND
//   sensor NAME KIND FRAME CHAIN END_EFFECTOR MODULE      ('-' for an empty field)
// Seeds: the models modelgen generates for the repository's assemblies, and the repository's
// URDF fixtures (no SRDF, no tables).
#include <cstdlib>
#include <sstream>

#include "concert/model/robot_model.hpp"
#include "concert/model_generation/generator.hpp"
#include "fuzz.hpp"
#include "model_pipeline.hpp"

namespace {

using namespace concert;

std::string field(std::string_view f) { return f == "-" ? std::string() : std::string(f); }
double number(std::string_view f) { return std::strtod(std::string(f).c_str(), nullptr); }

/// The tables of the input into `d`; throws model::ModelError for an unknown role or kind.
void read_tables(std::string_view tables, model::ModelDescription& d) {
  for (std::string_view line : fuzz::split(tables, '\n', 100000)) {
    std::vector<std::string_view> f;
    for (std::string_view w : fuzz::split(line, ' ', 64)) {
      if (!w.empty()) f.push_back(w);
    }
    if (f.empty()) continue;
    if (f[0] == "joint" && f.size() == 8) {
      d.joints.push_back({field(f[1]), field(f[2]), number(f[3]), number(f[4]), number(f[5]),
                          number(f[6]), number(f[7])});
    } else if (f[0] == "chain" && f.size() >= 5) {
      model::ChainInfo c{field(f[1]),
                         model::chain_role_from_string(f[2], "chain role"),
                         field(f[3]),
                         field(f[4]),
                         {}};
      for (size_t i = 5; i < f.size(); ++i) c.joints.push_back(field(f[i]));
      d.chains.push_back(std::move(c));
    } else if (f[0] == "ee" && f.size() == 6) {
      d.end_effectors.push_back({field(f[1]), field(f[2]), field(f[3]), field(f[4]),
                                 model::end_effector_kind_from_string(f[5], "end-effector kind")});
    } else if (f[0] == "sensor" && f.size() == 7) {
      d.sensor_frames.push_back({field(f[1]), model::sensor_kind_from_string(f[2], "sensor kind"),
                                 field(f[3]), field(f[4]), field(f[5]), field(f[6])});
    }
  }
}

std::string dash(const std::string& s) { return s.empty() ? "-" : s; }

/// A generated model as an input of this target.
std::string input_of(const model::ModelDescription& d) {
  std::ostringstream o;
  o.precision(17);
  o << d.urdf << '\0' << d.srdf << '\0';
  for (const model::JointLimits& j : d.joints) {
    o << "joint " << j.name << " " << dash(j.chain) << " " << j.lower << " " << j.upper << " "
      << j.velocity << " " << j.peak_torque << " " << j.continuous_torque << "\n";
  }
  for (const model::ChainInfo& c : d.chains) {
    o << "chain " << c.name << " " << model::to_string(c.role) << " " << c.base_link << " "
      << c.tip_link;
    for (const std::string& j : c.joints) o << " " << j;
    o << "\n";
  }
  for (const model::EndEffectorInfo& e : d.end_effectors) {
    o << "ee " << e.name << " " << dash(e.chain) << " " << e.frame << " " << dash(e.module_key)
      << " " << model::to_string(e.kind) << "\n";
  }
  for (const model::SensorFrame& s : d.sensor_frames) {
    o << "sensor " << s.name << " " << model::to_string(s.kind) << " " << s.frame << " "
      << dash(s.chain) << " " << dash(s.end_effector) << " " << dash(s.module_key) << "\n";
  }
  return o.str();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string_view> parts = fuzz::split(fuzz::text_of(data, size), '\0', 3);
  model::ModelDescription d;
  d.version = 7;
  d.urdf = parts[0];
  if (parts.size() > 1) d.srdf = parts[1];
  std::shared_ptr<const model::RobotModel> built;
  try {
    if (parts.size() > 2) read_tables(parts[2], d);
    built = model::RobotModel::build(std::move(d));
  } catch (const model::ModelError&) {
    return 0;
  }
  fuzz::exercise(*built);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  for (const std::filesystem::path& file : assembly_files()) {
    const simbus::Assembly assembly = simbus::load_assembly(file);
    const Database& d = database_of(assembly);
    const model_generation::GeneratedModel m = model_generation::ModelGenerator(d.db).generate(
        simbus::tree_from_assembly(assembly, d.catalog));
    seeds.add("model_" + file.stem().string(), input_of(m.description()));
  }
  for (const auto& dir : {source_dir() / "libs/kinematics/test/fixtures",
                          source_dir() / "tests/fixtures/urdf"}) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.path().extension() == ".urdf") seeds.add_file(entry.path(), source_dir());
    }
  }
  seeds.add_tokens(kXmlTokens);
  seeds.add_tokens({"joint ", "chain ", "ee ", "sensor ", "arm", "leg", "tool", "other", "drill",
                    "gripper", "sanding", "spraying", "camera", "wheel", "lidar", "sonar", "imu",
                    "force_torque", std::string(1, '\0')});
}
