#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include "nav/costmap.hpp"
#include "nav/global_planner.hpp"

namespace concert::nav {

/// A base velocity in the base frame.
struct BaseTwist {
  double vx{0.0};  ///< forward [m/s]
  double vy{0.0};  ///< left [m/s] (0 for a differential drive)
  double wz{0.0};  ///< yaw rate [rad/s]
};

/// The pose reached from `pose` (x [m], y [m], theta [rad], map frame) after holding the
/// base-frame `twist` for `dt` [s] (exact integration of a constant twist).
Eigen::Vector3d integrate_twist(const Eigen::Vector3d& pose, const BaseTwist& twist, double dt);

/// Local controller parameters: a regulated pure pursuit (nav2's RPP) with a holonomic variant.
struct ControllerParams {
  /// How the base moves: omni-steering (vx, vy, wz) or differential (vx, wz; turns in place).
  enum class Drive : std::uint8_t { kOmni, kDifferential };
  /// The platform's limits (per axis, symmetric).
  struct Limits {
    double max_vx{0.5};  ///< [m/s]
    double max_vy{0.5};  ///< [m/s] (unused for a differential drive)
    double max_wz{1.0};  ///< [rad/s]
    double max_ax{0.5};  ///< [m/s^2]
    double max_ay{0.5};  ///< [m/s^2]
    double max_aw{1.0};  ///< [rad/s^2]
  };

  Drive drive{Drive::kOmni};
  Limits limits;
  double desired_speed{0.5};  ///< cruise speed along the path [m/s]
  /// Lookahead = clamp(speed * lookahead_time, min_lookahead, max_lookahead) [s, m, m].
  double lookahead_time{1.5};
  double min_lookahead{0.3};
  double max_lookahead{0.9};
  /// Curvature regulation: below this turning radius the speed scales with radius / it [m].
  double regulated_min_radius{0.9};
  /// Proximity regulation: within this distance of an obstacle the speed scales down to
  /// proximity_gain * distance / proximity_distance [m, -].
  double proximity_distance{0.5};
  double proximity_gain{1.0};
  /// Lowest speed the regulations leave [m/s].
  double min_regulated_speed{0.1};
  /// Within approach_distance of the goal the speed falls linearly to min_approach_speed [m, m/s].
  double approach_distance{0.6};
  double min_approach_speed{0.03};
  /// Speed of the straight move off a start whose footprint covers an obstacle [m/s].
  double escape_speed{0.1};
  /// Goal tolerances: position [m], heading [rad].
  double xy_goal_tolerance{0.05};
  double yaw_goal_tolerance{2.0 * M_PI / 180.0};
  /// Heading controller: yaw rate = heading_gain * heading error [1/s].
  double heading_gain{1.5};
  /// Omni: above this heading error the speed along the path falls (to 20 % at 90 deg) [rad].
  double heading_slowdown_error{20.0 * M_PI / 180.0};
  /// Differential: above this heading error to the lookahead point, turn in place [rad].
  double rotate_in_place_error{45.0 * M_PI / 180.0};
  /// Footprint collision check along the forward-simulated command: step [s]; the robot keeps
  /// stop_margin [m] to the first colliding pose.
  double collision_check_step{0.05};
  double stop_margin{0.12};
  /// Stopped for an obstacle for longer than this [s] -> kBlocked (the caller replans).
  double blocked_timeout{2.0};
  /// Farther than this from the path -> kFailed [m].
  double max_path_deviation{1.0};
  /// Control period assumed for the first command and for gaps in the stamps [s].
  double control_period{0.05};
};

/// What the controller is doing.
enum class ControlStatus : std::uint8_t {
  kIdle,       ///< no path
  kFollowing,  ///< moving along the path (possibly slowed)
  kWaiting,    ///< stopped before an obstacle on the path, not yet blocked
  kReached,    ///< within both goal tolerances; zero command
  kBlocked,    ///< stopped before an obstacle for longer than blocked_timeout: replan
  kFailed,     ///< cannot follow the path (see reason); zero command
};

/// Short name of a status ("following", ...).
const char* to_string(ControlStatus status);

/// One control step's output.
struct ControlOutput {
  BaseTwist cmd;  ///< base-frame command, within the limits
  ControlStatus status{ControlStatus::kIdle};
  std::string reason;            ///< why blocked/failed (names the pose and the obstacle distance)
  double distance_to_goal{0.0};  ///< [m]
  double heading_error{0.0};     ///< to the goal heading [rad]
};

/// Regulated pure pursuit for the omni-steering base (commands vx, vy towards the lookahead
/// point, yaw towards the path's heading, the goal's at the end) and for a differential drive
/// (vx and wz on the pursuit arc; turns in place when the heading error is large). Speed is
/// regulated by curvature, proximity to obstacles and the approach to the goal, and limited by
/// the acceleration limits; the footprint is checked along the forward-simulated command and
/// the speed is cut so the robot can stop stop_margin before the first collision; when that
/// stops it, the translation alone (omni) or the turn alone is tried before waiting.
class LocalController {
 public:
  /// Throws std::invalid_argument naming a bad parameter.
  explicit LocalController(const ControllerParams& params = {});

  /// Follows `path` (from the global planner) from now on; resets the goal latch and the
  /// blocked timer. Throws std::invalid_argument on an empty path.
  void set_path(const Path& path);
  /// Forgets the path (status kIdle) and the last command.
  void reset();

  /// One control step at time `stamp` [s] with the robot at `pose` (map frame) on `costmap`
  /// (its obstacle layer updated from the latest scans).
  ControlOutput compute(const Costmap& costmap, const Eigen::Vector3d& pose, double stamp);

  /// Sets the acceleration limits (each > 0; throws std::invalid_argument naming a bad one),
  /// e.g. scaled to what the drives sustain with the posture the base carries. The velocity
  /// limits and the path stay.
  void set_acceleration_limits(double max_ax, double max_ay, double max_aw);

  [[nodiscard]] const ControllerParams& params() const { return params_; }
  [[nodiscard]] const BaseTwist& last_command() const { return last_cmd_; }

 private:
  [[nodiscard]] BaseTwist limit_acceleration(const BaseTwist& want, double dt) const;
  // Scale in [0, 1] of `cmd` that stops stop_margin before its first colliding pose within
  // max_tau [s at the full command].
  [[nodiscard]] double safe_scale(const Costmap& costmap, const Eigen::Vector3d& pose,
                                  const BaseTwist& cmd, double max_tau) const;
  ControlOutput stop(ControlOutput out);
  // The cycle of a path that starts with the footprint over an obstacle, until it is free.
  ControlOutput escape(const Costmap& costmap, const Eigen::Vector3d& pose, double dt, ControlOutput out);

  ControllerParams params_;
  Path path_;
  std::size_t progress_{0};  // index of the path pose nearest the robot
  // Where the path started with the footprint over an obstacle: how deep it may go into one
  // (Costmap::leaving_depth) until the footprint is free at any heading.
  std::optional<double> escape_depth_;
  bool escape_checked_{false};
  bool xy_latched_{false};
  std::optional<double> last_stamp_;
  std::optional<double> blocked_since_;
  BaseTwist last_cmd_;
};

}  // namespace concert::nav
