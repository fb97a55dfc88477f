#include "drill/drill_rig.hpp"

#include "concert/mobile_base/base_kinematics.hpp"
#include "drill/mission.hpp"

namespace concert::drill {

DrillRig::DrillRig(std::shared_ptr<const model::RobotModel> model)
    : model_(std::move(model)), data_(model_->kinematics().make_data()) {
  try {
    const model::EndEffectorInfo& drill = model_->tool(model::EndEffectorKind::kDrill);
    tool_ = drill.name;
    tcp_ = drill.frame;
    const model::SensorFrame& camera = model_->sensor(drill, model::SensorKind::kCamera);
    camera_ = camera.name;
    camera_frame_ = camera.frame;
  } catch (const model::ModelError& e) {
    // The model's errors begin with where they are ("model version 2: no drill tool ..."):
    // said once.
    std::string why = e.what();
    if (const std::string at = model_->where() + ": "; why.rfind(at, 0) == 0) why.erase(0, at.size());
    throw DrillError(model_->where() + " cannot drill: " + why);
  }
  standing_height_ = mobile_base::standing_height(*model_);
}

Eigen::VectorXd DrillRig::q(const JointPositions& state) const {
  if (state.names.size() != state.positions.size()) {
    throw DrillError("joint state has " + std::to_string(state.names.size()) + " names and " +
                     std::to_string(state.positions.size()) + " positions");
  }
  const kinematics::Model& k = model_->kinematics();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
  for (std::size_t i = 0; i < state.names.size(); ++i) {
    if (const auto j = k.joint_index(state.names[i])) q[*j] = state.positions[i];
  }
  return q;
}

Eigen::Isometry3d DrillRig::in_base(const Eigen::VectorXd& q, const std::string& frame) const {
  std::lock_guard lock(mutex_);
  return model_->kinematics().frame_pose(data_, q, frame);
}

Eigen::Isometry3d DrillRig::base_in_world(const Eigen::Vector3d& odometry) const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(odometry.x(), odometry.y(), standing_height_);
  t.linear() = Eigen::AngleAxisd(odometry.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

}  // namespace concert::drill
