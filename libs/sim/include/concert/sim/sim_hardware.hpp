#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "concert/hardware/hardware.hpp"
#include "concert/sim/drilling.hpp"
#include "concert/world/person_order.hpp"
#include "concert/sim/sensor_params.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/world/world.hpp"

namespace concert::sim {

using world::World;
using hardware::HardwareError;

/// Parameters of the simulated robot (MuJoCo).
struct SimParams {
  double timestep{0.001};            ///< physics step [s]; step(dt) runs round(dt / timestep) steps
  double position_stiffness{3000.0}; ///< drive gains in position mode [Nm/rad]
  double position_damping{100.0};    ///< [Nm s/rad]
  double velocity_gain{60.0};        ///< drive gain in velocity mode [Nm s/rad]
  double armature{0.1};              ///< reflected rotor inertia added to every actuated joint [kg m^2]
  double friction_scale{1.0};        ///< multiplies URDF <dynamics friction> (Coulomb, [Nm])
  double damping_scale{1.0};         ///< multiplies URDF <dynamics damping> (viscous, [Nm s/rad])
  double wheel_friction{1.0};        ///< sliding friction of wheel geoms [-]
  double robot_friction{0.5};        ///< sliding friction of other robot geoms [-]
  /// Sliding friction of the collision geoms of these links (link name -> [-]), which decides
  /// their contacts (MuJoCo geom priority 1: the contact takes this friction instead of the
  /// larger of the two geoms'). For a tool whose contact is not a dry block sliding on the
  /// wall, e.g. a running sanding disc (surface_finish). A name that is no link is an error.
  std::map<std::string, double> link_friction;
  /// Sliding friction of the sanding tools' links (SimHardware's `sanding_links`, unless
  /// link_friction names them): a running sanding disc, whose abrasive slides at the rim speed
  /// omega R, drags against the stroke with about mu v / (omega R): 0.8 x 0.1 m/s / 12 m/s =
  /// 0.007 for a 0.23 m disc at 1000 rpm and 0.1 m/s strokes (services/surface_finish README;
  /// MuJoCo's disc does not spin). Negative: not applied (a standing disc, robot_friction).
  double sanding_disc_friction{0.007};
  /// Floating (free) base: default true iff the model has steering+wheel legs.
  std::optional<bool> floating_base;
  Eigen::Vector3d base_position{0.0, 0.0, 0.0};  ///< [m]; z is computed for a floating base on the floor
  double base_yaw{0.0};                           ///< [rad]
  /// Joint -> [rad]/[m]; the others start at their homing position (SimulatedRobot::joint_homes;
  /// else 0, within the joint's limits).
  std::map<std::string, double> initial_positions;
  double position_noise{0.0};        ///< std-dev of the encoder noise [rad]
  double effort_noise{0.0};          ///< std-dev of the torque-sensor noise [Nm]
  unsigned seed{1};                  ///< noise seed
  /// ROS-style package roots for collision meshes: "package://NAME/rest" -> DIR/rest
  /// (e.g. {"concert_resources", "/work/shared/data/concert_resources"}). Meshes that do not
  /// resolve to an existing file are skipped; wheel links keep only their primitive shapes.
  std::map<std::string, std::string> package_paths;
  SensorParams sensors;              ///< simulated sensors (sensor_params.hpp)
  DrillingParams drilling;           ///< how walls resist drill bits (drilling.hpp)
};

/// MJCF text for a URDF placed in a world (exposed for tests and for debugging in MuJoCo's
/// viewer). Throws HardwareError naming the URDF element that cannot be simulated.
std::string urdf_to_mjcf(const std::string& urdf, const World& world, const SimParams& params);

/// The `sim` backend: the robot in MuJoCo. The drives' inner loops (impedance with torque
/// saturation at the URDF effort limit) run at the physics rate, as real drives do.
class SimHardware final : public hardware::Hardware {
 public:
  /// `sensors`: the sensors the robot carries (SimulatedRobot::sensors), simulated when
  /// params.sensors.enabled and delivered to the sink given to set_sensor_sink().
  /// `drill_bits`: the drill bits it carries (SimulatedRobot::drill_bits), which cut holes
  /// in the world's walls (drilling.hpp).
  /// `sanding_links`: the links of its sanding tools (SimulatedRobot::sanding_links), whose
  /// contacts get SimParams::sanding_disc_friction.
  /// A bare URDF carries no roles: its steering legs are found by their axes (detect_legs).
  SimHardware(const std::string& urdf, World world, SimParams params = {},
              std::vector<SensorMount> sensors = {}, std::vector<DrillBit> drill_bits = {},
              std::vector<std::string> sanding_links = {});
  /// An assembled robot (AssemblyBuilder): its URDF, sensors, drill bits, sanding links, and the
  /// steering legs its model names by role (SimulatedRobot::legs; by their axes when nullopt).
  /// Throws HardwareError naming a leg whose joints are not a steering axis over a wheel.
  SimHardware(SimulatedRobot robot, World world, SimParams params = {});
  ~SimHardware() override;
  SimHardware(const SimHardware&) = delete;
  SimHardware& operator=(const SimHardware&) = delete;

  [[nodiscard]] std::string backend() const override { return "sim"; }
  [[nodiscard]] const std::vector<std::string>& joint_names() const override;
  [[nodiscard]] std::uint64_t generation() const override;
  [[nodiscard]] hardware::MountedHardware mounted() const override;
  [[nodiscard]] std::uint64_t mounted_generation() const override;
  bool switch_prepared() override;
  void read(hardware::HardwareState& state) override;
  void write(const std::vector<hardware::DriveCommand>& commands) override;
  void step(double dt) override;
  /// Sensor threads start with the first sink (sensor_runtime: rendering and ray casting run
  /// off the control thread, in simulated time, skipping samples rather than delaying it).
  void set_sensor_sink(hardware::SensorSink* sink) override;
  /// The sensors of the robot mounted last (as mounted()).
  [[nodiscard]] std::vector<hardware::SensorInfo> sensors() const override;

  /// Hot swap, prepared on the calling thread (any thread but the control thread: URDF ->
  /// MJCF -> MuJoCo model and data) and switched in by the control thread's next
  /// switch_prepared(): the robot becomes `urdf` (the base pose and the joints of a bare URDF
  /// with the same name keep their state, within the new joint's limits; every drive holds
  /// position) and generation() increases; mounted()
  /// reports it at once. The same URDF again is no change (returns false). Throws
  /// HardwareError (nothing changes) if the URDF cannot be simulated.
  /// `sensors` and `drill_bits` are the new robot's (the old robot's sensors stop, the new
  /// ones start). Holes already drilled stay in the walls.
  bool swap_model(const std::string& urdf, std::vector<SensorMount> sensors = {},
                  std::vector<DrillBit> drill_bits = {},
                  std::vector<std::string> sanding_links = {});
  /// The same for an assembled robot, its legs by role as in the constructor. A joint's state
  /// belongs to its module (SimulatedRobot::joint_modules), as a drive's encoder does: a kept
  /// module's joint keeps it under whatever name the new model gives it; a joint whose module
  /// is new starts at its homing position, whatever the old robot's joint of that name did.
  bool swap_model(SimulatedRobot robot);
  /// Replaces the world the same way (keeps the robot state and the hardware generation).
  void set_world(const World& world);
  /// The latest world given (any thread).
  [[nodiscard]] World world() const;

  /// An external force on `link` (a MuJoCo body: fixed links may be merged into their parent,
  /// then name the parent) acting at `point` (world frame, [m]) with `force` (world frame, [N]),
  /// applied at every physics step until replaced or cleared: a person's hand on the robot in
  /// tests and benchmarks (services/collab's simulated person). Control thread only (between
  /// step() calls). Throws HardwareError for an unknown link or a non-finite value. A swap
  /// (switch_prepared) keeps it when the new model has the link, else clears it.
  void set_external_force(const std::string& link, const Eigen::Vector3d& force, const Eigen::Vector3d& point);
  void clear_external_force();

  /// Checks `order` (world/person_order.hpp) against the mounted robot (the link, someone gripping
  /// for a walk) and queues it for the next step() (any thread); returns what will happen.
  /// Throws HardwareError naming what is wrong, and nothing changes. The person lets go when the
  /// robot is swapped for another (a new world keeps the grip), and when the link falls too far
  /// behind.
  std::string person(const world::PersonOrder& order);
  /// The person after the latest step() (any thread; the control thread never waits for it).
  [[nodiscard]] world::PersonReport person_report() const;

  // Ground truth, for tests and benchmarks.
  [[nodiscard]] double time() const;
  [[nodiscard]] Eigen::Isometry3d link_pose(const std::string& link) const;
  /// Pose of the root link in the world.
  [[nodiscard]] Eigen::Isometry3d base_pose() const;
  /// The root link's pose in the world and the simulated time after the latest step(), safe
  /// from any thread (the control thread never waits for a reader: a step that finds the
  /// snapshot being read leaves the previous one). Time 0 and identity before the first step.
  struct BaseTruth {
    double time{0.0};                                         ///< simulated time [s]
    Eigen::Isometry3d pose{Eigen::Isometry3d::Identity()};  ///< world_T_root
  };
  [[nodiscard]] BaseTruth base_truth() const;
  /// Every hole the drill bits have cut so far, in the order they were started (any thread;
  /// the control thread refreshes the copy when a hole opens or deepens by 0.1 mm).
  [[nodiscard]] std::vector<SimHole> holes() const;
  /// Total contact force the world exerts on `links` [N], world frame.
  [[nodiscard]] Eigen::Vector3d contact_force_on(const std::vector<std::string>& links) const;
  [[nodiscard]] const std::string& mjcf() const;
  [[nodiscard]] const std::string& urdf() const;
  [[nodiscard]] bool floating_base() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::sim
