#include "concert/model/dds/conversions.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "concert/model/dds/pose.hpp"

namespace concert::model::dds {
namespace {

constexpr double kWireInfinity = 1e300;

double to_wire(double v) {
  if (std::isinf(v)) return v > 0 ? kWireInfinity : -kWireInfinity;
  return v;
}

double from_wire(double v) {
  if (v >= kWireInfinity) return std::numeric_limits<double>::infinity();
  if (v <= -kWireInfinity) return -std::numeric_limits<double>::infinity();
  return v;
}

}  // namespace

ModelDescription to_description(const msg::RobotModel& m) {
  const std::string where = "RobotModel v" + std::to_string(m.version()) + " ";
  ModelDescription d;
  d.version = m.version();
  d.content_hash = m.content_hash();
  d.tree_version = m.tree_version();
  d.urdf = m.urdf();
  d.srdf = m.srdf();
  d.config_yaml = m.config_yaml();
  d.modules = m.modules();
  for (const msg::JointInfo& j : m.joints()) {
    d.joints.push_back({j.name(), j.chain(), from_wire(j.lower()), from_wire(j.upper()),
                        j.velocity(), j.peak_torque(), j.continuous_torque()});
  }
  for (std::size_t i = 0; i < m.chains().size(); ++i) {
    const msg::ChainInfo& c = m.chains()[i];
    d.chains.push_back(
        {c.name(),
         chain_role_from_string(c.role(), where + "chains[" + std::to_string(i) + "].role"),
         c.base_link(), c.tip_link(), c.joints()});
  }
  for (std::size_t i = 0; i < m.end_effectors().size(); ++i) {
    const msg::EndEffectorInfo& e = m.end_effectors()[i];
    d.end_effectors.push_back(
        {e.name(), e.chain(), e.frame(), e.module_key(),
         end_effector_kind_from_string(e.kind(),
                                       where + "end_effectors[" + std::to_string(i) + "].kind")});
  }
  for (std::size_t i = 0; i < m.sensor_frames().size(); ++i) {
    const msg::SensorFrameInfo& s = m.sensor_frames()[i];
    d.sensor_frames.push_back(
        {s.name(),
         sensor_kind_from_string(s.kind(), where + "sensor_frames[" + std::to_string(i) + "].kind"),
         s.frame(), s.chain(), s.end_effector(), s.module_key()});
  }
  return d;
}

msg::RobotModel to_msg(const ModelDescription& d, int64_t stamp_ns) {
  msg::RobotModel m;
  m.version(static_cast<uint32_t>(d.version));
  m.content_hash(d.content_hash);
  m.tree_version(static_cast<uint32_t>(d.tree_version));
  m.stamp_ns(stamp_ns);
  m.urdf(d.urdf);
  m.srdf(d.srdf);
  m.config_yaml(d.config_yaml);
  m.modules(d.modules);
  for (const JointLimits& j : d.joints) {
    msg::JointInfo w;
    w.name(j.name);
    w.chain(j.chain);
    w.lower(to_wire(j.lower));
    w.upper(to_wire(j.upper));
    w.velocity(j.velocity);
    w.peak_torque(j.peak_torque);
    w.continuous_torque(j.continuous_torque);
    m.joints().push_back(std::move(w));
  }
  for (const ChainInfo& c : d.chains) {
    msg::ChainInfo w;
    w.name(c.name);
    w.role(std::string(to_string(c.role)));
    w.base_link(c.base_link);
    w.tip_link(c.tip_link);
    w.joints(c.joints);
    m.chains().push_back(std::move(w));
  }
  for (const EndEffectorInfo& e : d.end_effectors) {
    msg::EndEffectorInfo w;
    w.name(e.name);
    w.chain(e.chain);
    w.frame(e.frame);
    w.module_key(e.module_key);
    w.kind(std::string(to_string(e.kind)));
    m.end_effectors().push_back(std::move(w));
  }
  for (const SensorFrame& s : d.sensor_frames) {
    msg::SensorFrameInfo w;
    w.name(s.name);
    w.kind(std::string(to_string(s.kind)));
    w.frame(s.frame);
    w.chain(s.chain);
    w.end_effector(s.end_effector);
    w.module_key(s.module_key);
    m.sensor_frames().push_back(std::move(w));
  }
  return m;
}

}  // namespace concert::model::dds

namespace concert::model::dds {

Eigen::Isometry3d to_isometry(const msg::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position().x(), p.position().y(), p.position().z());
  const Eigen::Quaterniond q(p.orientation().w(), p.orientation().x(), p.orientation().y(),
                             p.orientation().z());
  t.linear() = q.norm() > 1e-9 ? q.normalized().toRotationMatrix() : Eigen::Matrix3d::Zero();
  return t;
}

msg::Vector3 to_vector_msg(const Eigen::Vector3d& v) {
  msg::Vector3 out;
  out.x(v.x());
  out.y(v.y());
  out.z(v.z());
  return out;
}

msg::Pose to_pose_msg(const Eigen::Isometry3d& t) {
  msg::Pose p;
  p.position(to_vector_msg(t.translation()));
  const Eigen::Quaterniond q(t.linear());
  p.orientation().x(q.x());
  p.orientation().y(q.y());
  p.orientation().z(q.z());
  p.orientation().w(q.w());
  return p;
}

}  // namespace concert::model::dds
