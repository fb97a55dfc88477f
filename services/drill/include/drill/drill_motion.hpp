#pragma once
// Closed-loop drilling of one hole (paper section 5.4.3, eq. 3): the Cartesian reference of the
// drill bit's tip for the arm's Cartesian impedance controller, phase by phase (align in front
// of the hole, drill along the axis, retract). Plain C++, no DDS.
//
// Frames: everything here is in one fixed frame, the frame the robot's Cartesian controller
// takes targets in (the robot's root link: the base stands still while drilling). A hole frame
// has its origin where the hole starts on the surface and z along the outward normal; the bit's
// tip frame (the drill's TCP) has z along the bit. Depth d is how far the tip is behind the
// surface along -z of the hole frame (negative in front of it).
//
// Eq. 3: the reference is the hole's axis point at depth d_ref, d_ref = d_ref + v_drill * dt,
// with the x-y error to the hole removed; with visual servoing the hole frame is re-estimated
// from each camera frame (observe()) until the bit is in the wall, when the hole itself holds it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <string>

namespace concert::drill {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Tuning of the drilling motion. Thrust comes from the impedance's axial stiffness times the
/// reference's lead on the tip; max_lead bounds it (axial_stiffness * max_lead).
struct DrillParams {
  double standoff{0.04};           ///< [m] tip in front of the surface when aligned
  double approach_speed{0.05};     ///< [m/s] of the reference while aligning and retracting
  double approach_turn{0.3};       ///< [rad/s] of the reference while aligning
  double align_tolerance{0.0015};  ///< [m] tip off its aligned position, counted as aligned
  double align_angle{0.02};        ///< [rad] bit axis off the hole's axis, counted as aligned
  double settle_time{0.3};         ///< [s] aligned this long before drilling starts
  double feed_rate{0.01};          ///< [m/s] v_drill
  double max_lead{0.015};          ///< [m] reference ahead of the tip along the bit at most
  double servo_jump{
      0.02};  ///< [m] an observed hole further than this from the current estimate is an outlier
  /// The surface is where the bit feels it: the reference leads the tip by at least this much
  /// [m] (stiffness x 4 mm = 32 N, over the wall's 20 N threshold) while the tip advances at
  /// less than half the feed rate. The depth is counted from there, not from the surface the
  /// camera measured (off by 2-20 mm after a base move, which would leave holes that short).
  double contact_lead{0.004};
  /// [m] beyond the depth asked (from the camera's surface) the bit feeds looking for the wall
  /// before the hole fails.
  double contact_search{0.03};
  double align_timeout{15.0};    ///< [s]
  double drill_timeout{30.0};    ///< [s]
  double retract_timeout{15.0};  ///< [s]
  /// Translational stiffness is the same along every axis: the robot's controller takes a
  /// diagonal in the fixed frame, and an isotropic one needs no rotation to the hole's axes.
  double stiffness{8000.0};         ///< [N/m]
  double damping{500.0};            ///< [N s/m]
  double angular_stiffness{300.0};  ///< [N m/rad]
  double angular_damping{20.0};     ///< [N m s/rad]
};

/// The most the bit pushes on the wall along its axis [N]: the axial stiffness times the
/// reference's largest lead, plus the damping at the feed rate (125 N with the defaults). The
/// planner checks the arm's torques with it at every posture the drill asks for.
inline double thrust_bound(const DrillParams& p) {
  return p.stiffness * p.max_lead + p.damping * p.feed_rate;
}

/// The same drilling with the largest lead scaled by `lead` (0 < lead <= 1), about that
/// fraction of the thrust, for the holes the arm cannot hold the full thrust at: half the lead
/// (the default) pushes 65 N with the defaults, of 125 N, and the simulated wall then lets the
/// bit advance at about 7 mm/s instead of 10; morphology A reaches a row at 0.5 m with the whole
/// body only under 100-150 N checked, not 200 N, and its row at 0.35 m only under 50-100 N
/// (kLightestLead). The lead stays kLeadOverContact above contact_lead, or the bit would no
/// longer feel the wall. The feed rate stays: at half of it too the bit's contact with the wall
/// (contact_lead reached while the tip advances at under half the feed rate) can be missed,
/// and a hole then goes 77.5 mm deep for 30 mm asked.
inline constexpr double kLeadOverContact = 0.0015;  // [m]
inline constexpr double kLightestLead = 0.35;
inline DrillParams light_drilling(DrillParams p, double lead = 0.5) {
  p.max_lead = std::max(p.max_lead * lead, p.contact_lead + kLeadOverContact);
  return p;
}

/// A Cartesian impedance reference for the tip, in the fixed frame.
struct CartesianReference {
  Eigen::Isometry3d pose{Eigen::Isometry3d::Identity()};
  Vector6d twist{Vector6d::Zero()};  ///< [m/s, rad/s] feed-forward velocity of the reference
  Vector6d stiffness{Vector6d::Zero()};
  Vector6d damping{Vector6d::Zero()};
};

/// One hole's motion. Call start_*() then update() every control period with the tip's
/// measured pose and the robot's time of that measurement [s] (its timeouts, settle time and
/// ramps count the robot's time, not the wall's); send the returned reference to the robot.
class DrillMotion {
 public:
  enum class Phase { kIdle, kAligning, kDrilling, kRetracting, kDone, kFailed };

  explicit DrillMotion(DrillParams params = {});

  /// Aligns the tip `standoff` in front of `hole`, the bit along -z of the hole frame.
  void start_align(const Eigen::Isometry3d& hole, const Eigen::Isometry3d& tip, double now);
  /// Drills to `depth` [m] behind the surface, the surface taken where the bit first meets it
  /// (DrillParams::contact_lead: the hole frame moves along its axis there); `servo`:
  /// observe() moves the hole until then.
  void start_drill(double depth, bool servo, const Eigen::Isometry3d& tip, double now);
  /// Pulls the tip back to `standoff` in front of the surface.
  void start_retract(const Eigen::Isometry3d& tip, double now);

  /// The drives' thermal foldback, from the engine's measure of their RMS torque: the share of
  /// the tuned thrust the drilling may push with, in [0, 1]. Below 1 the reference leads the tip
  /// less, down to light_drilling's floor (the bit still feels the wall); at 0, once the bit has
  /// met the wall, the feed stops with the bit at rest in the hole (no thrust) and the drilling's
  /// time limit waits with it, for at most another drill_timeout (then the hole fails, saying
  /// so). Kept across phases until set again.
  void set_thrust_share(double share);
  [[nodiscard]] double thrust_share() const { return thrust_share_; }
  /// Robot time the feed stood still at share 0 in this drilling [s].
  [[nodiscard]] double paused() const { return paused_; }

  /// A new estimate of the hole (visual servoing): used while aligning and, with servo, while
  /// the tip is still in front of the surface; an outlier (servo_jump) is ignored. Returns
  /// whether it was used.
  bool observe(const Eigen::Isometry3d& hole);

  /// The base moved (`new_T_old`: the old base frame in the new one, from odometry): the hole
  /// and the reference, kept in the base frame, move with the world, not with the base.
  void move_base(const Eigen::Isometry3d& new_T_old);

  /// The reference for now; advances the phase (kAligning -> kDone when settled, kDrilling ->
  /// kDone at depth, kRetracting -> kDone at the standoff; kFailed on a timeout, with reason()).
  CartesianReference update(const Eigen::Isometry3d& tip, double now);

  [[nodiscard]] Phase phase() const { return phase_; }
  [[nodiscard]] const std::string& reason() const { return reason_; }
  [[nodiscard]] const Eigen::Isometry3d& hole() const { return hole_; }
  /// The tip's depth behind the hole's surface [m] (negative in front).
  [[nodiscard]] double depth_of(const Eigen::Isometry3d& tip) const;
  /// The tip's offset from the hole's axis [m].
  [[nodiscard]] double lateral_error(const Eigen::Isometry3d& tip) const;
  /// Deepest depth reached in this drilling [m].
  [[nodiscard]] double reached() const { return reached_; }
  /// Whether the bit has felt the surface in this drilling, and how far from where the camera
  /// put it [m] (positive: further into the wall).
  [[nodiscard]] bool contact() const { return contact_; }
  [[nodiscard]] double contact_offset() const { return contact_offset_; }

 private:
  [[nodiscard]] Eigen::Isometry3d axis_pose(double depth, const Eigen::Isometry3d& tip) const;
  CartesianReference reference(double depth, double feed, const Eigen::Isometry3d& tip) const;
  void fail(const std::string& why);

  DrillParams params_;
  Phase phase_{Phase::kIdle};
  std::string reason_;
  Eigen::Isometry3d hole_{Eigen::Isometry3d::Identity()};
  double started_{0.0};
  double last_{0.0};
  Eigen::Isometry3d ref_{Eigen::Isometry3d::Identity()};  ///< the reference while aligning
  double depth_ref_{0.0};                                 ///< reference depth along the axis [m]
  double target_depth_{0.0};
  double settled_since_{-1.0};
  double reached_{0.0};
  bool servo_{false};
  bool contact_{false};
  double contact_offset_{0.0};
  double last_depth_{0.0};
  double axial_speed_{0.0};  ///< the tip's feed along the bit, filtered [m/s]
  double thrust_share_{1.0};
  double paused_{0.0};
};

const char* to_string(DrillMotion::Phase phase);

}  // namespace concert::drill
