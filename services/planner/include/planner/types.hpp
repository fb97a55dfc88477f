#pragma once
// Plain data of the planner core (paper section 5.4.2): the robot model it is built from,
// parameters, requests, trajectories and results. No DDS, no generated IDL types.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "concert/model/description.hpp"

namespace concert::planner {

/// A model, request or environment the planner cannot use; what() names the field or item.
class PlannerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The model as received (libs/model): the planner has no model type of its own.
using ModelDescription = model::ModelDescription;
/// An end-effector of the model (libs/model), selected by role and kind.
using EndEffectorInfo = model::EndEffectorInfo;

/// Parameters of the planner core (loaded from YAML by the adapter).
struct Params {
  // Task (paper section 5.4.2).
  double camera_distance = 0.6;      ///< d: camera frame to wall along the normal [m]
  /// per request (PlanRequest::view_slant > 0): a look from any side, the camera's axis through
  /// each area's centre from view_near to camera_distance [m] away, at most view_slant [rad]
  /// off the area's normal
  double view_slant = 0.0;
  double view_near = 0.0;             ///< [m] see view_slant
  double contact_force = 200.0;      ///< expected drilling force along the tool axis [N]
  double torque_margin = 1.0;        ///< allowed fraction of the continuous torque [-]
  /// A goal posture (NSPG) keeps each arm joint this far inside its position limits [rad or m],
  /// at most a tenth of the joint's range: the Cartesian phases that start there (a drill's
  /// align and thrust, visual servoing) move the arm on, and a joint past its limit stops the
  /// robot (the safety service's position rule). Paths and explicit joint goals use the limits.
  double posture_limit_margin = 0.05;

  // World.
  double floor_height = 0.0;         ///< [m] world z of the floor
  /// World z of the base link [m]; NaN: from the model (lowest leg collision on the floor).
  double base_height = std::numeric_limits<double>::quiet_NaN();
  double octomap_resolution = 0.05;  ///< [m]
  double environment_padding = 0.03; ///< robot shapes grown by this against the world [m]
  /// [m] radius of the drill bit's collision cylinder, from each drill's TCP back to where its
  /// module's shapes end (the module database gives the drill's body, not its bit); 0: no bit.
  /// Padded by environment_padding sideways and backwards, not beyond its tip.
  double drill_bit_radius = 0.008;
  /// A start standing up to this far inside the map (odometry drift) is first moved out: the
  /// nearest base pose clear of the map (x, y within this [m], yaw within this [rad] per metre),
  /// the move prepended to the path; 0: such a start is refused.
  double start_tolerance = 0.05;
  /// A start with links inside each other (self collision) is first moved out by jiggling the
  /// arm joints by up to this [rad or m], the move prepended; 0: such a start is refused.
  double start_joint_tolerance = 0.1;
  double floor_clearance = 0.02;     ///< non-leg shapes stay this far above the floor [m]
  double base_range = 3.0;           ///< base x, y sampled within start +- this [m]
  bool fixed_base = false;           ///< per request (PlanRequest::fixed_base): the base keeps its start pose
  double base_travel = 0.0;          ///< per request (PlanRequest::base_travel) [m and rad]; 0: no bound
  /// per request (PlanRequest::tip_distance > 0): the task puts the tool's tip (its TCP frame)
  /// at camera_distance on the area's normal, z along -normal, instead of its camera
  bool tip_task = false;
  /// per request (PlanRequest::tip_reach), with tip_task: the static torques are also checked
  /// with the tip moved this far [m] along the task axis (into the wall), the base standing
  double tip_reach = 0.0;

  // Map from the sensors (paper section 5.4.1; planner/sensor_map.hpp).
  /// What the service's map is built from: "world" (the world topic / --world file), "sensors"
  /// (the robot's lidars, ray-cast), "both" (the world's obstacles and the sensors' together).
  std::string environment_source = "world";
  double sensor_map_period = 1.0;    ///< service: the sensor map is updated and published at most this often [s]
  double sensor_max_range = 6.0;     ///< returns farther than this [m] clear their ray up to it and mark nothing
  double sensor_self_padding = 0.05; ///< robot shapes grown by this [m]: returns inside them are the robot's own
  double sensor_floor_band = 0.05;   ///< returns below floor_height + this [m] are the floor: they clear, never occupy
  /// service: a period's lidar revolutions and depth frames are used only if the base and every
  /// joint moved slower than this all along it [m/s, rad/s]
  double sensor_max_speed = 0.05;
  int sensor_depth_frames = 5;       ///< service: the latest depth frames of a camera averaged per map update (>= 1)
  int sensor_depth_stride = 4;       ///< depth images: every n-th pixel in u and v is ray-cast (>= 1)
  double sensor_depth_min_valid = 0.5;  ///< depth averaging: fraction of the frames that must read a pixel (0..1]

  // Planning. Time budgets are CPU seconds of the planning thread, not wall seconds, so a plan
  // does not depend on what else loads the machine.
  double planning_time = 2.0;        ///< per goal, NSPG included [s CPU]
  double path_attempt_time = 0.5;    ///< path search per goal posture before another posture is tried [s CPU]
  double check_resolution = 0.02;    ///< largest step between checked states [rad or m]
  int simplify_iterations = 50;      ///< shortcutting attempts after RRT-Connect
  int sample_iterations = 4;         ///< Gauss-Newton steps pulling every other RRT sample toward feasibility (0: uniform)
  uint64_t seed = 1;                 ///< random seed of NSPG and OMPL

  // NSPG.
  int nspg_seeds = 256;              ///< seeds tried per goal at most (start posture first; nspg_time usually ends it first)
  int nspg_screen = 24;              ///< random arm postures drawn per random seed (closest kept)
  int nspg_iterations = 40;          ///< Levenberg-Marquardt iterations per seed
  double nspg_time = 1.6;            ///< NSPG time budget per goal [s CPU] (of planning_time)
  int nspg_enough = 1;               ///< stop after this many valid postures
  double warm_up_time = 2.0;         ///< service: per height of the background warm-up after each model [s] (0: none)
  /// Warm-up: the arm's way from the parked arm to each remembered posture [s CPU]. A search that
  /// runs out stores the posture without a way, and later plans near it cannot replay one; on
  /// morphology B's low postures the searches take 0.23-4.4 s (0.43-0.46 s for some), so with a
  /// budget near those times what is remembered depends on the machine's speed.
  double warm_up_path_time = 0.5;
  int nspg_memory = 128;             ///< goal postures remembered per model as seeds for similar heights (0: off)
  /// Models whose posture memory is kept after a swap, by content hash (the least recently used
  /// model's is dropped first): a crew swapping the drill off and back on finds the postures of
  /// its earlier missions. The current model's memory always counts; 1 keeps no other.
  int memory_models = 4;
  double nspg_tolerance = 1e-3;      ///< task error accepted [m, rad]
  double nspg_distance_weight = 1.0; ///< cost of the distance to the start [1/rad]
  double nspg_singularity_weight = 0.5;  ///< cost of 1/manipulability of the arm [-]

  // Time parameterisation.
  double velocity_scale = 0.5;       ///< fraction of each joint's velocity limit [-]
  double joint_acceleration = 1.0;   ///< [rad/s^2]
  double base_linear_velocity = 0.4; ///< [m/s]
  double base_linear_acceleration = 0.5;  ///< [m/s^2]
  double base_angular_velocity = 0.5;     ///< [rad/s]
  double base_angular_acceleration = 1.0; ///< [rad/s^2]
  double sample_period = 0.02;       ///< output trajectory sample period [s]
  /// The arm drives' RMS torque over the thermal window stays within this fraction of their
  /// continuous torque along every trajectory, |tau| within the peak (inverse dynamics with the
  /// base's accelerations); segments are stretched until it does, at most max_drive_stretch x
  /// longer, and a path that still does not is refused (0: not checked) [-].
  double drive_torque_fraction = 1.0;
  double max_drive_stretch = 4.0;   ///< [-], >= 1
};

/// Which constraint rejected a state.
enum class Constraint { kNone, kJointLimit, kSelfCollision, kEnvironmentCollision, kFloor, kTorqueLimit };

/// Result of a state validity check.
struct Validity {
  Constraint constraint = Constraint::kNone;
  std::string detail;  ///< joint or link pair / link and obstacle concerned
  [[nodiscard]] bool valid() const { return constraint == Constraint::kNone; }
};

/// Name of a constraint ("joint limit", "self collision", ...).
const char* to_string(Constraint constraint);

/// A box in the world (a wall or an obstacle).
struct WorldBox {
  std::string name;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();      ///< full extents [m]
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< centre [m]
  double yaw = 0.0;                                    ///< [rad]
};

/// A vertical cylinder in the world.
struct WorldCylinder {
  std::string name;
  double radius = 0.0;                                 ///< [m]
  double height = 0.0;                                 ///< [m]
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< centre [m]
};

/// World description (walls/boxes, cylinders), as in the robot service's world file.
struct World {
  std::vector<WorldBox> boxes;
  std::vector<WorldCylinder> cylinders;
};

/// A whole-body trajectory sample: q over the planned joints.
struct TrajectoryPoint {
  double time = 0.0;     ///< [s] from the trajectory start
  Eigen::VectorXd q;     ///< [m, m, rad, rad...]
  Eigen::VectorXd qd;    ///< [m/s, m/s, rad/s, rad/s...]
};

/// Time-parameterised whole-body trajectory. joint_names: base_x, base_y, base_yaw, then the
/// arm joints of the model.
struct Trajectory {
  std::vector<std::string> joint_names;
  std::vector<TrajectoryPoint> points;
  [[nodiscard]] double duration() const { return points.empty() ? 0.0 : points.back().time; }
};

/// Outcome of a request or of one goal.
enum class Status { kSucceeded, kNoModel, kStaleModel, kInvalidRequest, kInvalidStart, kUnreachable, kNoPath };
const char* to_string(Status status);

/// A drilling area goal: frame with z along the outward surface normal (paper section 5.4).
struct Goal {
  Eigen::Isometry3d area = Eigen::Isometry3d::Identity();  ///< world frame
};

/// A planning request: goals in FIFO order.
struct PlanRequest {
  uint64_t request_id = 0;
  uint64_t model_version = 0;     ///< must equal the planner's model version
  std::string end_effector;       ///< tool end-effector name; empty: the arm's tool (by role)
  std::vector<Goal> goals;
  /// Camera frame to each area along its normal [m]; 0: Params::camera_distance. The drill
  /// service asks for the camera close to the wall to put the bit at a hole.
  double camera_distance = 0.0;
  /// > 0: a look at each area's centre from any side: the camera's optical axis through the
  /// centre, the camera between view_near and camera_distance (0: Params::camera_distance) from
  /// it and at most this far [rad] off the area's normal, rolled any way. The drill's look at a
  /// mark from where its base stands for a low hole: on morphology A no posture holds the camera
  /// on a low mark's normal from there, many see it from beside it, 0.8-1.1 m away.
  /// Not with tip_distance.
  double view_slant = 0.0;
  double view_near = 0.0;  ///< [m] the camera at least this far from the area's centre (view_slant)
  /// > 0: the tool's tip (its TCP frame), not its camera, goes this far [m] in front of each
  /// area on its normal, z along -normal; camera_distance is then unused. The drill service's
  /// hole postures: the posture the planner checks (torques with the drilling force, clearance)
  /// is then the one the bit drills from. With the camera on the hole's normal instead, the
  /// bit stands beside it (the drill's camera is 0.11 m off the bit) and the alignment's
  /// Cartesian move reaches out to a posture nobody checked: on morphology A the shoulder
  /// J2_E then needs its peak torque and the safety layer stops the robot.
  double tip_distance = 0.0;
  /// With tip_distance: how far [m] the bit goes on from the posture along -normal (to the wall
  /// and into it); the static torques are checked there too, the base standing. 0: not checked.
  double tip_reach = 0.0;
  /// Force the tool pushes along its axis at the goal postures [N], checked against the torques;
  /// 0: Params::contact_force. The drill service sends its own thrust bound (the impedance's
  /// stiffness times the reference's largest lead) with a margin (services/drill's
  /// checked_thrust), or a lighter thrust for a placement checked again at half of it.
  double contact_force = 0.0;
  /// No goals: the arm goes to its homing posture (the SRDF's `home` group state, joints it does
  /// not name at 0, clamped into the limits), the base standing: the transport posture nav
  /// drives with, where a swapped-in module's joints start. Planned like any path (collision
  /// free, timed within the drives); refused with the reason when that posture is not free
  /// where the robot stands.
  bool home = false;
  /// No goals, not with `home`: these arm joints to these positions, the joints not named
  /// keeping their start positions, the base standing (a task's start posture, e.g. collab's
  /// carrying posture). Planned like `home`; refused naming the joint when it is not an arm
  /// joint of the model or its position is beyond the joint's limits.
  std::vector<std::pair<std::string, double>> posture;
  /// The base keeps its start pose: only the arm moves (the drill service's hole postures:
  /// a base that moves lets odometry drift between holes).
  bool fixed_base = false;
  /// Robot shapes grown against the map [m]; 0: Params::environment_padding. The drill service
  /// keeps the base 10 cm from the wall: odometry drifts a few cm per whole-body move.
  double environment_padding = 0.0;
  /// The base ends at most this far from its start [m] and turned at most this much [rad]; 0:
  /// anywhere within Params::base_range of the start and the goal. The drill service bounds a
  /// hole's whole-body posture: odometry drifts with every centimetre and degree the base moves
  /// (a hole posture that spins the demo base by 2.3 rad leaves it 5 cm off).
  double base_travel = 0.0;
};

/// Result for one goal.
struct GoalResult {
  std::size_t index = 0;
  Status status = Status::kNoPath;
  std::string reason;             ///< empty on success
  Eigen::VectorXd goal_q;         ///< planned joints (see Trajectory::joint_names)
  Trajectory trajectory;
  double nspg_seconds = 0.0;      ///< goal posture generation time [s]
  double plan_seconds = 0.0;      ///< path search + simplification + timing [s]
  std::string load;               ///< the goal posture's heaviest joint load (fraction of its continuous torque), e.g. "J2_E 0.91 with the drilling force"
  std::string drives;             ///< the arm drives along the trajectory (DriveReport::summary)
  std::string path_method;        ///< how the path was found: "direct", "projected line", "arm, then drive", "drive, then arm" (or
                                  ///< with a "remembered arm path"), "RRT-Connect"
};

/// Result of a request.
struct PlanResult {
  uint64_t request_id = 0;
  uint64_t model_version = 0;
  Status status = Status::kNoPath;  ///< kSucceeded when every goal succeeded
  std::string reason;
  std::string note;  ///< how the request was planned when not as configured (e.g. without the padding)
  std::vector<GoalResult> goals;
};

}  // namespace concert::planner
