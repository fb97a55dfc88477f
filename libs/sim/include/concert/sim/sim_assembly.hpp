#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "concert/model/description.hpp"
#include "concert/sim/drilling.hpp"
#include "concert/sim/sensor_params.hpp"
#include "concert/topology/types.hpp"

namespace concert::sim {

/// A steering leg of the simulated robot, named by the model's roles (a chain of role leg,
/// model::RobotModel::legs()): the steering joint over its wheel joint and the wheel's radius.
struct SimLeg {
  std::string steering_joint;
  std::string wheel_joint;
  double wheel_radius{0.0};  ///< [m]
};

/// What the simulator needs to stand in for an assembled robot.
struct SimulatedRobot {
  std::string urdf;             ///< physics model of the assembly (modelgen's URDF)
  topology::EscScan scan;       ///< the scan the EtherCAT master would report (faults applied)
  topology::ModuleTree tree;    ///< the tree the assembly describes
  std::string source;           ///< assembly file
  std::vector<SensorMount> sensors;  ///< the sensors its modules carry (sensor frames of its model)
  std::vector<DrillBit> drill_bits;  ///< the bits of its drill end-effectors (their TCP links)
  /// The links moved with its sanding tools (the subtree of the last joint moving each sanding
  /// end-effector's TCP: the tool and its flange), for SimParams::sanding_disc_friction.
  std::vector<std::string> sanding_links;
  /// The TCP links of its gripper end-effectors: what a simulated person grips (person.hpp).
  std::vector<std::string> gripper_tcps;
  /// The steering legs by role (the wheels that roll on the floor). nullopt for a bare URDF,
  /// which carries no roles: the simulator then finds them by their axes (mobile_base::detect_legs).
  std::optional<std::vector<SimLeg>> legs;
  /// Moving joint -> the module it belongs to: its key and robot_id (the ESC's), else its key
  /// and place in the tree (and which of the module's joints, for a module with several). A hot
  /// swap carries a joint's state by this, never by the joint's name, which another morphology
  /// may give to another module's joint. Empty for a bare URDF.
  std::map<std::string, std::string> joint_modules;
  /// Moving joint -> the robot_id of its module's ESC (-1: its module has none): how a drive
  /// board on the EtherCAT ring is told apart from the others (libs/ethercat's robot on the
  /// virtual ring). Empty for a bare URDF.
  std::map<std::string, int32_t> joint_robot_ids;
  /// Moving joint -> its homing position, within its limits: where a joint whose module is new
  /// in a hot swap starts.
  std::map<std::string, double> joint_homes;
};

/// The simulated sensors of a model's sensor frames: cameras (RGB-D), lidars, sonars, IMUs;
/// other sensor kinds (force-torque, ...) are not simulated here and are left out.
std::vector<SensorMount> sensor_mounts(const std::vector<model::SensorFrame>& frames);

/// Turns an assembly file (libs/simbus format) into the simulated robot, with the module
/// databases given (EscCatalog + module descriptions). Immutable; build() is const.
class AssemblyBuilder {
 public:
  /// Loads the databases; throws std::runtime_error naming the folder on failure.
  explicit AssemblyBuilder(const std::vector<std::filesystem::path>& module_db_dirs);
  ~AssemblyBuilder();
  AssemblyBuilder(AssemblyBuilder&&) noexcept;
  AssemblyBuilder& operator=(AssemblyBuilder&&) noexcept;

  /// Throws std::runtime_error naming the file and module on any problem.
  [[nodiscard]] SimulatedRobot build(const std::filesystem::path& assembly_file) const;
  /// Same from YAML text; `source` names it in messages.
  [[nodiscard]] SimulatedRobot build_from_text(const std::string& yaml, const std::string& source) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::sim
