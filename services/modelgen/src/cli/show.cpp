// `concert model show`: prints the live (latched) robot model from DDS.

#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/json.hpp"
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
    // Every field as the IDL names it; the description files themselves are left out (they are
    // `concert topic echo concert/model/robot_model`'s, or the bundle's).
    idl::Json j = concert::dds::to_json(*m);
    for (const char* text : {"urdf", "srdf", "config_yaml"}) j.erase(text);
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
