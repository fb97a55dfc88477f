#pragma once
// The limits table of a model and THE LIMITS RULE: which limit each consumer enforces.
//
// The rule (stated once here and in libs/model/README.md; every service applies it through
// these functions, so robot, safety and planner agree by construction):
//
//  * position: the robot clamps commands to [lower, upper]; safety stops beyond
//    [lower - tolerance, upper + tolerance]; the planner keeps every state within [lower, upper].
//  * velocity: the robot saturates commands at the velocity limit; safety stops beyond
//    velocity x (1 + margin); the planner plans within velocity x velocity_scale (<= 1).
//  * torque: the robot's drives saturate at the PEAK torque; the legs' (steering, wheels) fold
//    back to the CONTINUOUS torque as their RMS over the thermal window nears it
//    (folded_back_torque, the I^2 t protection of a servo drive); safety stops at once beyond peak x (1 + margin), and when
//    the RMS of the torque over the thermal window exceeds CONTINUOUS x (1 + margin); the
//    planner keeps static/planned torques within the CONTINUOUS torque (x torque_margin <= 1).
//
// Why: the peak torque is what a drive can deliver for a short time, the continuous torque
// what it can deliver without overheating. A transient above the continuous torque (an arm
// accelerating, a contact) is normal operation and must not stop the robot; a torque above
// the peak cannot come from a healthy drive, and a load above the continuous torque held for
// the thermal window overheats the drive: both stop. The planner keeps what it controls (the
// static load of every planned posture) within the continuous torque, so the robot can hold
// any planned posture indefinitely. What the planner cannot foresee on the base (wheels
// scrubbing while the legs steer, a base pushing an obstacle) meets the leg drive's foldback
// first: the wheel slips or the steering lags instead of the whole robot being stopped. An arm
// joint keeps its peak: one that yields moves the tool, so there safety's stop is the end.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "concert/model/description.hpp"

namespace concert::model {

/// Thermal window of the sustained-torque rule [s]: the time constant of the exponentially
/// weighted mean of tau^2 (a first-order I^2 t thermal model of the drive).
inline constexpr double kThermalWindow = 5.0;

/// Torque the robot's drives saturate at [N m]: the peak torque.
inline double drive_torque_limit(const JointLimits& j) { return j.peak_torque; }
/// RMS torque over the thermal window, as a fraction of the continuous torque, from which a
/// drive folds its torque limit back [-].
inline constexpr double kFoldbackStart = 0.9;
/// The torque limit of a drive whose RMS torque over the thermal window is `rms` [N m]: the
/// peak torque up to kFoldbackStart x continuous, then falling linearly to the continuous
/// torque, reached when the RMS is the continuous torque (and kept above it). A drive held to
/// it keeps its RMS within the continuous torque (plus one sample's share of the peak), so the
/// safety layer's sustained bound, continuous x (1 + margin), is never reached by the load
/// alone. Servo drives protect their motors this way (I^2 t foldback).
double folded_back_torque(const JointLimits& j, double rms);
/// Torque the planner keeps static/planned loads within [N m]: the continuous torque.
inline double planning_torque_limit(const JointLimits& j) { return j.continuous_torque; }
/// |tau| beyond which safety stops at once [N m]: peak x (1 + margin).
inline double instant_torque_bound(const JointLimits& j, double margin) {
  return j.peak_torque * (1.0 + margin);
}
/// RMS torque over the thermal window beyond which safety stops [N m]:
/// continuous x (1 + margin).
inline double sustained_torque_bound(const JointLimits& j, double margin) {
  return j.continuous_torque * (1.0 + margin);
}
/// |qd| beyond which safety stops at once [rad/s]: velocity x (1 + margin).
inline double velocity_bound(const JointLimits& j, double margin) {
  return j.velocity * (1.0 + margin);
}
/// True when q [rad] is beyond [lower - tolerance, upper + tolerance] (or not finite).
bool position_violated(const JointLimits& j, double q, double tolerance);

/// RMS of one joint's torque over the thermal window (exponentially weighted, time constant
/// kThermalWindow), fed with samples at increasing times. Starts cold (RMS 0).
class ThermalLoad {
 public:
  explicit ThermalLoad(double window = kThermalWindow);
  /// Adds |tau| [N m] measured `dt` [s] after the previous sample (the first sample's dt is
  /// ignored). Returns the RMS torque [N m] now.
  double add(double tau, double dt);
  /// RMS torque [N m] now.
  [[nodiscard]] double rms() const;
  /// The drive has held |tau| [N m] for long: its RMS is |tau|, the next add() weighs by dt.
  void hold(double tau) {
    mean_square_ = tau * tau;
    started_ = true;
  }
  void reset() {
    mean_square_ = 0.0;
    started_ = false;
  }

 private:
  double window_;
  double mean_square_ = 0.0;
  bool started_ = false;
};

/// The limits table of one model version: one row per moving joint, checked on construction.
class LimitsTable {
 public:
  LimitsTable() = default;
  /// Checks every row; throws ModelError naming `where` (e.g. "model version 3"), the joint and
  /// the column: lower > upper, velocity or peak torque not positive, continuous torque not in
  /// (0, peak], a joint listed twice.
  LimitsTable(std::vector<JointLimits> rows, const std::string& where);

  [[nodiscard]] const std::vector<JointLimits>& rows() const { return rows_; }
  [[nodiscard]] std::size_t size() const { return rows_.size(); }
  /// The row of `joint`, or nullptr.
  [[nodiscard]] const JointLimits* find(std::string_view joint) const;
  /// The row of `joint`; throws ModelError listing the joints.
  [[nodiscard]] const JointLimits& at(std::string_view joint) const;

 private:
  std::vector<JointLimits> rows_;
  std::string where_;
};

}  // namespace concert::model
