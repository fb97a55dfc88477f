#include "concert/model/same_arm.hpp"

#include <Eigen/Geometry>
#include <optional>

namespace concert::model {

bool same_frame_pose(const RobotModel& before, const RobotModel& after, const std::string& frame,
                     const std::vector<std::string>& names, const std::vector<double>& positions, double tolerance,
                     double angle_tolerance) {
  if (names.size() != positions.size()) return false;
  const auto pose = [&](const RobotModel& m) -> std::optional<Eigen::Isometry3d> {
    const kinematics::Model& k = m.kinematics();
    if (!k.has_frame(frame)) return std::nullopt;
    Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (const auto j = k.joint_index(names[i])) q[*j] = positions[i];
    }
    kinematics::Data data = k.make_data();
    return k.frame_pose(data, q, frame);
  };
  const std::optional<Eigen::Isometry3d> a = pose(before), b = pose(after);
  if (!a || !b) return false;
  const double turned = Eigen::AngleAxisd(a->linear().transpose() * b->linear()).angle();
  return (a->translation() - b->translation()).norm() <= tolerance && turned <= angle_tolerance;
}

}  // namespace concert::model
