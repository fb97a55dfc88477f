#pragma once
// Whether a new model version keeps the arm a task is using: a task in contact with a wall (a
// drill bit in a hole, a sanding disc on plaster) may leave it under the new version only when
// the new model puts its tool where the old one does at the joints measured now. A module
// swapped elsewhere (a wheel, a camera) passes; another arm fails, because its joints no longer
// say where the tool is.

#include <string>
#include <vector>

#include "concert/model/robot_model.hpp"

namespace concert::model {

/// Whether `after` puts `frame` where `before` does at the joint positions measured now (`names`,
/// `positions`; the joints either model has but the state does not name at 0): within
/// `tolerance` [m] and `angle_tolerance` [rad], both in the kinematics' root frame. False when
/// either model has no such frame or `names` and `positions` differ in length.
[[nodiscard]] bool same_frame_pose(const RobotModel& before, const RobotModel& after, const std::string& frame,
                                   const std::vector<std::string>& names, const std::vector<double>& positions,
                                   double tolerance = 0.005, double angle_tolerance = 0.01);

}  // namespace concert::model
