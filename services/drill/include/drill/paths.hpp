#pragma once
// Joint-space paths the drill sends the robot besides the planner's: from where the robot is
// measured to stand onto a planned posture, a planned path backwards, the way back through every
// hole's posture, with the base kept where it stands when it is only a few mm off. Plain C++, no
// DDS: the adapter converts the planner's trajectories into these and these into commands.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "drill/drill_rig.hpp"

namespace concert::drill {

/// One sample of a whole-body path: base_x, base_y, base_yaw and arm joints, as named by its Path.
struct PathSample {
  double time{0.0};  ///< [s] from the path's start
  std::vector<double> position;
  std::vector<double> velocity;
};

/// A path as planned or made here: joint names and samples.
struct Path {
  std::vector<std::string> names;
  std::vector<PathSample> samples;
};

/// A joint state with the odometry measured with it (robot clock).
struct JointSample {
  std::int64_t stamp_ns{0};
  JointPositions joints;
  Eigen::Vector3d odometry{0, 0, 0};  ///< x, y, yaw
};

/// How the paths are timed and when the base is kept where it stands.
struct PathTiming {
  double settle_min{1.0};   ///< [s] the least time of a settle, and the lead-in of a reversed path
  double base_kept{0.03};   ///< [m, rad] a base this close to a posture's stays where it stands
  double joint_speed{0.5};  ///< [rad/s] a settle's slow joint speed
  double base_speed{0.2};   ///< [m/s] a settle's slow base speed
  double speed_share{3.0};  ///< a settle runs at 1/speed_share of those speeds
};

/// The measured state of `names` (base joints from odometry) as a sample at t = 0, to go on to
/// the planned sample `towards` (same names): its base_yaw within half a turn of that one's
/// (odometry's yaw is wrapped, the planner's is not: a robot facing -x measures -3.14 where its
/// plan says 3.13, and the straight line between them would turn the base a whole turn).
[[nodiscard]] PathSample sample_here(const std::vector<std::string>& names, const JointSample& s,
                                     const PathSample& towards);

/// The base joints of every sample of `path` set to `here`'s: the base stays where it stands
/// while the arm goes on. With `bound` > 0 only when `here`'s base is within `bound` [m, rad] of
/// every sample's (a few mm of creep or tracking error, not a move); true when the base was kept.
bool keep_base(const std::vector<std::string>& names, const PathSample& here, std::vector<PathSample>& path,
               double bound = 0.0);

/// Time to go straight from `from` to `to` at a share of a slow joint speed, at least
/// settle_min (the Cartesian phases can leave a joint far off its posture, a wrist turned about
/// the bit: a fixed second would drive it past its velocity limit).
[[nodiscard]] double settle_time(const std::vector<std::string>& names, const PathSample& from,
                                 const PathSample& to, const PathTiming& timing = {});

/// `path` backwards after `back`: settle_min to reach its end, then its samples in reverse
/// order with their velocities negated, times from `t` on (`t` left at the path's start).
void append_reversed(std::vector<PathSample>& back, const Path& path, double& t, const PathTiming& timing = {});

/// From the measured state back through every path of `chain` (each hole's posture as reached,
/// first to last), reversed; the base kept where it stands when every posture had it within
/// base_kept. `chain` must not be empty.
[[nodiscard]] std::vector<PathSample> return_path(const std::vector<Path>& chain, const JointSample& s,
                                                  const PathTiming& timing = {});

/// Straight from `here` onto `p`'s last posture, at rest there (settle_time).
struct Settle {
  std::vector<PathSample> samples;
  bool base_kept{false};  ///< the base stays where it stands (within base_kept of the posture's)
  double base_off{0.0};   ///< then: how far it stands from the posture's [m]
  double base_turn{0.0};  ///< and turned from it [rad]
};
[[nodiscard]] Settle settle_path(const Path& p, const PathSample& here, const PathTiming& timing = {});

/// From the end of `look` (a look at the hole's mark planned from `posture`'s end) back onto
/// `posture`'s end: the look's path backwards, not straight across in joint space (that can
/// sweep the tool along the wall when odometry puts the wall a few cm off), then at rest there.
/// Straight (settle_path) when the two paths do not share their joints or the look has no path.
[[nodiscard]] std::vector<PathSample> back_from_look(const Path& look, const Path& posture, const JointSample& s,
                                                     const PathTiming& timing = {});

}  // namespace concert::drill
