#pragma once
// Sanding force control (paper section 5.7): on top of the Cartesian impedance, a PD on the force
// error moves the impedance reference along the tool's z (z_ee, into the wall): an admittance law
// for that direction, impedance in the others. The setpoint ramps up from zero first (the
// paper's approach "linearly increasing the force"). Statistics and a plot of a force trace (the
// paper's Fig. 24). No DDS.

#include <string>
#include <vector>

#include "surface_finish/types.hpp"

namespace concert::surface_finish {

struct AdmittanceParams {
  double kp{0.004};        ///< reference speed per newton of force error [m/(N s)]
  double kd{0.0002};       ///< reference speed per newton per second of its rate [m/N]
  double ramp_time{2.0};   ///< the setpoint ramps from 0 over this time [s]
  double max_speed{0.05};  ///< the reference moves at most this fast [m/s]
  double max_offset{0.05}; ///< nor further than this from where it started [m]
  double filter{0.01};     ///< time constant of the force error's derivative filter [s]
};

/// The law. Not thread-safe.
class ForceAdmittance {
 public:
  /// Throws FinishError for non-positive gains or times.
  ForceAdmittance(double setpoint, AdmittanceParams params = {});
  /// One control period: the measured contact force along z_ee [N] (pushing on the wall is
  /// positive) -> the reference's offset along z_ee from where it started [m].
  double update(double force, double dt);
  [[nodiscard]] double offset() const { return offset_; }
  /// The setpoint now (ramping) [N].
  [[nodiscard]] double setpoint() const;
  [[nodiscard]] bool ramped() const { return time_ >= params_.ramp_time; }

 private:
  double target_;
  AdmittanceParams params_;
  double time_{0.0};
  double offset_{0.0};
  double error_{0.0};
  double rate_{0.0};
  bool first_{true};
};

/// One sample of a force trace.
struct ForceSample {
  double t{0.0};          ///< [s]
  double estimated{0.0};  ///< from the joint torques [N]
  double truth{0.0};      ///< the simulator's contact force [N] (NaN when unknown)
  bool stroke{false};     ///< during the sanding strokes (statistics count these only)
};

struct ForceStats {
  double mean{0.0};          ///< [N], of the estimate during strokes
  double min{0.0}, max{0.0};
  double std_dev{0.0};
  double within_fraction{0.0};  ///< of the stroke time within +-tolerance of the setpoint
  double time_outside{0.0};     ///< [s]
  double truth_mean{0.0};       ///< of the simulator's force during strokes
  double estimate_error_rms{0.0};  ///< estimate vs truth [N]
  double duration{0.0};         ///< stroke time [s]
};

/// Statistics of the stroke samples of `trace` against `setpoint` +- `tolerance` [N]. Throws
/// FinishError for a trace without stroke samples.
ForceStats force_stats(const std::vector<ForceSample>& trace, double setpoint, double tolerance);

/// A plot of the trace like the paper's Fig. 24 (estimate, truth, setpoint and the band) as a
/// PNG. Throws FinishError if it cannot write.
void write_force_png(const std::vector<ForceSample>& trace, double setpoint, double tolerance, const std::string& path);

}  // namespace concert::surface_finish
