// `concert model show`: prints the live (latched) robot model from DDS.

#include <chrono>
#include <cmath>
#include <iomanip>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "modelgen/cli.hpp"

namespace concert::modelgen {

int show_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  double timeout_s = 3.0;
  for (size_t i = 1; i < args.size(); ++i) {
    if (args[i] == "--timeout" && i + 1 < args.size()) {
      try {
        size_t pos = 0;
        timeout_s = std::stod(args[++i], &pos);
        if (pos != args[i].size() || !(timeout_s >= 0.0)) throw std::invalid_argument("bad");
      } catch (const std::exception&) {
        err << "concert model show: --timeout '" << args[i] << "': expected seconds >= 0\n";
        return 2;
      }
    } else {
      err << "concert model show: unknown argument '" << args[i] << "'\nusage: concert model show [--timeout S]\n";
      return 2;
    }
  }
  try {
    concert::dds::Participant participant({.name = "concert_model_show"});
    concert::dds::Reader<msg::RobotModel> reader(participant, concert::dds::topics::robot_model);
    const auto m = reader.wait(std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000.0)));
    if (!m) {
      err << "concert model show: no robot model received within " << timeout_s << " s on domain " << participant.domain_id()
          << " (is concert_modelgen running?)\n";
      return 1;
    }
    out << "robot model version " << m->version() << " (" << m->content_hash() << "), from module tree version " << m->tree_version()
        << "\n";
    out << "modules (" << m->modules().size() << "):";
    for (size_t i = 0; i < m->modules().size(); ++i) out << " " << i << ":" << m->modules()[i];
    out << "\nchains (" << m->chains().size() << "):\n";
    for (const msg::ChainInfo& c : m->chains()) {
      out << "  " << c.name() << " (" << c.role() << ") " << c.base_link() << " -> " << c.tip_link() << ":";
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
      out << ", velocity " << j.velocity() << " rad/s, torque peak " << j.peak_torque() << " / continuous "
          << j.continuous_torque() << " N m\n";
    }
    out << "end-effectors (" << m->end_effectors().size() << "):\n";
    for (const msg::EndEffectorInfo& e : m->end_effectors()) {
      out << "  " << e.name() << " (" << e.kind() << ") chain " << e.chain() << " frame " << e.frame() << " module "
          << e.module_key() << "\n";
    }
    out << "sensor frames (" << m->sensor_frames().size() << "):\n";
    for (const msg::SensorFrameInfo& f : m->sensor_frames()) {
      out << "  " << f.name() << " (" << f.kind() << ") frame " << f.frame() << " on " << (f.end_effector().empty() ? "-" : f.end_effector())
          << " module " << f.module_key() << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    err << "concert model show: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace concert::modelgen
