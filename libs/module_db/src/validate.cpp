#include <Eigen/SVD>
#include <cmath>
#include <set>
#include <utility>

#include "concert/module_db/module_db.hpp"
#include "internal.hpp"

namespace concert::module_db::detail {

void fail(const std::filesystem::path& file, const std::string& field, const std::string& what) {
  throw ModuleDbError(file.filename().string() + ": " + field + ": " + what);
}

namespace {

bool finite(const Pose& p) { return p.matrix().allFinite(); }

/// Checks that the rotation part is a rotation (to 1e-3) and replaces it by the nearest exact
/// rotation: the public files round entries to 6 digits (0.707107), and every consumer (URDF rpy,
/// FK) must see the same orthonormal matrix.
void check_rotation(Pose& p, const std::filesystem::path& file, const std::string& field) {
  if (!finite(p)) fail(file, field, "not finite");
  const Eigen::Matrix3d r = p.linear();
  if (!(r.transpose() * r).isIdentity(1e-3) || std::abs(r.determinant() - 1.0) > 1e-3 ||
      std::abs(p.matrix()(3, 3) - 1.0) > 1e-12 || !p.matrix().row(3).head<3>().isZero(0.0)) {
    fail(file, field, "rotation part is not a rotation matrix");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  p.linear() = svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace

void validate_and_normalise(ModuleDescription& m, const std::filesystem::path& file) {
  if (m.bodies.empty()) fail(file, "bodies", "at least one body required");
  const int nb = static_cast<int>(m.bodies.size());
  std::set<std::string> names;
  for (size_t i = 0; i < m.bodies.size(); ++i) {
    const Body& b = m.bodies[i];
    const std::string f = "bodies[" + std::to_string(i) + "]";
    if (!names.insert(b.name).second) fail(file, f + ".name", "duplicate body name '" + b.name + "'");
    if (!std::isfinite(b.inertial.mass) || b.inertial.mass < 0.0) fail(file, f + ".mass", "must be finite and >= 0");
    if (!b.inertial.com.allFinite()) fail(file, f + ".com", "not finite");
    if (!b.inertial.inertia.allFinite()) fail(file, f + ".inertia", "not finite");
    if (!b.inertial.inertia.isApprox(b.inertial.inertia.transpose(), 1e-6) &&
        !(b.inertial.inertia - b.inertial.inertia.transpose()).isZero(1e-9)) {
      fail(file, f + ".inertia", "not symmetric");
    }
    for (const auto& [shapes, field] :
         {std::pair{&b.visuals, ".visual"}, {&b.collisions, ".collision"}}) {
      for (size_t k = 0; k < shapes->size(); ++k) {
        const auto& rgba = (*shapes)[k].rgba;
        if (rgba && !(rgba->array() >= 0.0 && rgba->array() <= 1.0).all()) {
          fail(file, f + field + "[" + std::to_string(k) + "].rgba",
               "components must be within 0..1");
        }
      }
    }
  }
  int inputs = 0;
  for (size_t i = 0; i < m.connectors.size(); ++i) {
    Connector& c = m.connectors[i];
    const std::string f = "connectors[" + std::to_string(i) + "]";
    if (c.body < 0 || c.body >= nb) fail(file, f + ".body", "no such body");
    check_rotation(c.pose, file, f + ".pose");
    if (c.role == ConnectorRole::kInput) ++inputs;
    if (m.is_end_effector() && c.role == ConnectorRole::kOutput) c.role = ConnectorRole::kTcp;
    if ((c.role == ConnectorRole::kInput || c.role == ConnectorRole::kOutput) && c.size.empty()) {
      fail(file, f + ".size", "missing");
    }
  }
  if (inputs > 1) fail(file, "connectors", "more than one input connector");
  if (inputs == 0 && !m.is_hub()) fail(file, "connectors", "no input connector");
  std::set<int> children;
  for (size_t i = 0; i < m.joints.size(); ++i) {
    JointDescription& j = m.joints[i];
    const std::string f = "joints[" + std::to_string(i) + "]";
    if (j.parent_body < 0 || j.parent_body >= nb) fail(file, f + ".parent", "no such body");
    if (j.child_body < 0 || j.child_body >= nb) fail(file, f + ".child", "no such body");
    if (j.parent_body == j.child_body) fail(file, f + ".child", "same body as parent");
    if (!children.insert(j.child_body).second) fail(file, f + ".child", "body has two parent joints");
    check_rotation(j.pose_parent, file, f + ".pose_parent");
    check_rotation(j.pose_child, file, f + ".pose_child");
    if (!j.axis.allFinite() || std::abs(j.axis.norm() - 1.0) > 1e-6) fail(file, f + ".axis", "must be a unit vector");
    if (j.actuated()) {
      if (std::isnan(j.limits.lower) || std::isnan(j.limits.upper) || j.limits.lower > j.limits.upper) {
        fail(file, f + ".limits", "lower position limit above upper");
      }
      if (j.type != JointType::kContinuous &&
          (!std::isfinite(j.limits.lower) || !std::isfinite(j.limits.upper))) {
        fail(file, f + ".limits",
             "lower and upper position limits required (a revolute joint without both is "
             "continuous)");
      }
      if (!std::isfinite(j.limits.velocity) || j.limits.velocity <= 0.0) fail(file, f + ".limits.velocity", "must be > 0");
      if (!std::isfinite(j.limits.peak_torque) || j.limits.peak_torque <= 0.0) {
        fail(file, f + ".limits.peak_torque", "must be > 0");
      }
      if (j.limits.continuous_torque && (*j.limits.continuous_torque <= 0.0 || *j.limits.continuous_torque > j.limits.peak_torque)) {
        fail(file, f + ".limits.continuous_torque", "must be > 0 and <= peak_torque");
      }
      if (!std::isfinite(j.gear_ratio) || j.gear_ratio <= 0.0) fail(file, f + ".gear_ratio", "must be > 0");
    }
  }
  // Bodies form a tree hanging from the root body.
  const int root = m.root_body();
  if (children.count(root) != 0) fail(file, "joints", "the root body '" + m.bodies[static_cast<size_t>(root)].name + "' is a joint's child");
  if (static_cast<int>(children.size()) != nb - 1) {
    fail(file, "joints", "bodies are not connected into one tree (" + std::to_string(nb) + " bodies, " +
                             std::to_string(children.size()) + " child joints)");
  }
  for (size_t i = 0; i < m.frames.size(); ++i) {
    const std::string f = "frames[" + std::to_string(i) + "]";
    if (m.frames[i].body < 0 || m.frames[i].body >= nb) fail(file, f + ".body", "no such body");
    check_rotation(m.frames[i].pose, file, f + ".pose");
  }
}

}  // namespace concert::module_db::detail
