#pragma once
// What the spray and sand runs share (internal to concert_surface_finish_sim): the assembly's
// robot for MuJoCo with its model, and the drive commands of the robot service's trajectory
// controller (position mode, velocity and gravity feed-forward).

#include <Eigen/Core>

#include <filesystem>
#include <memory>
#include <vector>

#include "concert/hardware/hardware.hpp"
#include "concert/model/robot_model.hpp"
#include "concert/sim/sim_assembly.hpp"

namespace concert::surface_finish::detail {

struct SimRobot {
  sim::SimulatedRobot robot;                    ///< URDF and module tree for libs/sim
  std::shared_ptr<const model::RobotModel> model;  ///< as modelgen builds it (version 1)
};

/// The robot of `assembly` with the first of `module_dbs` generating its model.
SimRobot load_sim_robot(const std::filesystem::path& assembly, const std::vector<std::filesystem::path>& module_dbs);

/// Position-mode commands (q_ref with qd_ref as feed-forward, gravity as effort) for every
/// hardware joint i with a model index index[i] >= 0; the others get a default position command.
void position_commands(const std::vector<int>& index, const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref,
                       const Eigen::VectorXd& gravity, std::vector<hardware::DriveCommand>& cmd);

}  // namespace concert::surface_finish::detail
