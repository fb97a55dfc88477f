#pragma once
// The drill as one model version mounts it: the drill end-effector's TCP (the bit's tip), its
// camera, and where they are for a joint state and an odometry pose. Plain C++, no DDS.
//
// Frames: "base" is the robot's root link (the frame the robot service's Cartesian controller
// takes targets in); "world" is the odometry frame with z up and the floor at z = 0: the base
// stands at (x, y, yaw) of the odometry, its root link the standing height above the floor.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "concert/kinematics/model.hpp"
#include "concert/model/robot_model.hpp"

namespace concert::drill {

/// A joint state: names and positions (any order, any superset of the model's joints).
struct JointPositions {
  std::vector<std::string> names;
  std::vector<double> positions;
};

class DrillRig {
 public:
  DrillRig(const DrillRig&) = delete;
  DrillRig& operator=(const DrillRig&) = delete;
  /// The drill of `model`. Throws DrillError naming what is missing: no drill end-effector
  /// (listing what the arm carries), no camera on it.
  explicit DrillRig(std::shared_ptr<const model::RobotModel> model);

  [[nodiscard]] const model::RobotModel& model() const { return *model_; }
  [[nodiscard]] std::uint64_t version() const { return model_->version(); }
  [[nodiscard]] const std::string& tool() const { return tool_; }      ///< e.g. "drill_E"
  [[nodiscard]] const std::string& tcp_frame() const { return tcp_; }  ///< e.g. "tcp_E"
  [[nodiscard]] const std::string& camera() const {
    return camera_;
  }  ///< sensor name, e.g. "camera_E"
  [[nodiscard]] const std::string& camera_frame() const {
    return camera_frame_;
  }  ///< optical frame
  /// Height of the root link above the floor when the base stands on its wheels [m] (0
  /// for a fixed arm).
  [[nodiscard]] double standing_height() const { return standing_height_; }

  /// q in the fixed-base kinematics' order; joints the state lacks are 0. Throws DrillError
  /// if names and positions differ in length.
  [[nodiscard]] Eigen::VectorXd q(const JointPositions& state) const;
  /// Pose of a link in the base frame.
  [[nodiscard]] Eigen::Isometry3d in_base(const Eigen::VectorXd& q, const std::string& frame) const;
  [[nodiscard]] Eigen::Isometry3d tip_in_base(const Eigen::VectorXd& q) const {
    return in_base(q, tcp_);
  }
  [[nodiscard]] Eigen::Isometry3d camera_in_base(const Eigen::VectorXd& q) const {
    return in_base(q, camera_frame_);
  }
  /// world_T_base for an odometry pose (x, y [m], yaw [rad]).
  [[nodiscard]] Eigen::Isometry3d base_in_world(const Eigen::Vector3d& odometry) const;

 private:
  std::shared_ptr<const model::RobotModel> model_;
  std::string tool_, tcp_, camera_, camera_frame_;
  double standing_height_{0.0};
  mutable std::mutex
      mutex_;  // guards data_: the camera callbacks and the control thread share a rig
  mutable kinematics::Data data_;
};

}  // namespace concert::drill
