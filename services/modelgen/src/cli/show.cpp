// `concert model show`: prints the live (latched) robot model from DDS.

#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "modelgen/cli.hpp"

namespace concert::modelgen {

int show(const cli::DdsOptions& o, std::ostream& out) {
  const double timeout_s = o.timeout_s;
  concert::dds::Participant participant({.name = "concert_model_show", .domain_id = o.domain_id()});
  concert::dds::Reader<msg::RobotModel> reader(participant, concert::dds::topics::robot_model);
  const auto m = reader.wait(std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000.0)));
  if (!m) {
    std::ostringstream what;
    what << "no robot model received within " << timeout_s << " s on domain "
         << participant.domain_id() << " (is concert_modelgen running?)";
    throw cli::Failure(what.str());
  }
  if (o.json) {
    nlohmann::ordered_json j = {{"version", m->version()},
                                {"content_hash", m->content_hash()},
                                {"tree_version", m->tree_version()},
                                {"modules", m->modules()}};
    j["chains"] = nlohmann::ordered_json::array();
    for (const msg::ChainInfo& c : m->chains()) {
      j["chains"].push_back({{"name", c.name()},
                             {"role", c.role()},
                             {"base_link", c.base_link()},
                             {"tip_link", c.tip_link()},
                             {"joints", c.joints()}});
    }
    j["joints"] = nlohmann::ordered_json::array();
    for (const msg::JointInfo& jt : m->joints()) {
      j["joints"].push_back({{"name", jt.name()},
                             {"chain", jt.chain()},
                             {"lower", jt.lower()},
                             {"upper", jt.upper()},
                             {"velocity", jt.velocity()},
                             {"peak_torque", jt.peak_torque()},
                             {"continuous_torque", jt.continuous_torque()}});
    }
    j["end_effectors"] = nlohmann::ordered_json::array();
    for (const msg::EndEffectorInfo& e : m->end_effectors()) {
      j["end_effectors"].push_back({{"name", e.name()},
                                    {"kind", e.kind()},
                                    {"chain", e.chain()},
                                    {"frame", e.frame()},
                                    {"module_key", e.module_key()}});
    }
    j["sensor_frames"] = nlohmann::ordered_json::array();
    for (const msg::SensorFrameInfo& f : m->sensor_frames()) {
      j["sensor_frames"].push_back({{"name", f.name()},
                                    {"kind", f.kind()},
                                    {"frame", f.frame()},
                                    {"end_effector", f.end_effector()},
                                    {"module_key", f.module_key()}});
    }
    out << j.dump(2) << "\n";
    return 0;
  }
  out << "robot model version " << m->version() << " (" << m->content_hash()
      << "), from module tree version " << m->tree_version() << "\n";
  out << "modules (" << m->modules().size() << "):";
  for (size_t i = 0; i < m->modules().size(); ++i) out << " " << i << ":" << m->modules()[i];
  out << "\nchains (" << m->chains().size() << "):\n";
  for (const msg::ChainInfo& c : m->chains()) {
    out << "  " << c.name() << " (" << c.role() << ") " << c.base_link() << " -> " << c.tip_link()
        << ":";
    for (const std::string& j : c.joints()) out << " " << j;
    out << "\n";
  }
  out << "joints (" << m->joints().size() << "):\n";
  for (const msg::JointInfo& j : m->joints()) {
    out << "  " << j.name() << " chain " << j.chain();
    // Continuous joints travel with limits of +-1e300 (no bound).
    if (j.lower() <= -1e299 && j.upper() >= 1e299) {
      out << " continuous";
    } else {
      out << " position [" << j.lower() << ", " << j.upper() << "] rad";
    }
    out << ", velocity " << j.velocity() << " rad/s, torque peak " << j.peak_torque()
        << " / continuous " << j.continuous_torque() << " N m\n";
  }
  out << "end-effectors (" << m->end_effectors().size() << "):\n";
  for (const msg::EndEffectorInfo& e : m->end_effectors()) {
    out << "  " << e.name() << " (" << e.kind() << ") chain " << e.chain() << " frame "
        << e.frame() << " module " << e.module_key() << "\n";
  }
  out << "sensor frames (" << m->sensor_frames().size() << "):\n";
  for (const msg::SensorFrameInfo& f : m->sensor_frames()) {
    out << "  " << f.name() << " (" << f.kind() << ") frame " << f.frame() << " on "
        << (f.end_effector().empty() ? "-" : f.end_effector()) << " module " << f.module_key()
        << "\n";
  }
  return 0;
}

}  // namespace concert::modelgen
