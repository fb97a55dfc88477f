#pragma once
// Spray runs in the MuJoCo simulator (libs/sim), without DDS: the assembly's robot stands in
// front of a wall, the areas are computed for its model, the serpentine is planned and tracked
// at 1 kHz by the simulated drives (position mode with velocity feed-forward and the model's
// gravity torques, as the robot service's trajectory controller commands them), and the
// deposition model is fed the simulator's true TCP pose every millisecond. For the system test
// of the physics, the benchmark and the demo.

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "surface_finish/areas.hpp"
#include "surface_finish/deposition.hpp"
#include "surface_finish/serpentine.hpp"

namespace concert::surface_finish {

struct SprayRunParams {
  std::filesystem::path assembly;                 ///< robot with a spraying tool
  std::vector<std::filesystem::path> module_dbs;  ///< module database folders
  std::string area{"all"};                        ///< area id the rectangles lie in
  /// Rectangles to spray one after the other (wall coordinates); each reshapes `area`.
  std::vector<Rect> rects;
  ToolSpec tool{Task::kSpray, 0.3, 0.1, 0.1};
  PathParams path;
  AreaParams areas;
  /// Where the robot stands: this far from the wall face [m]; NaN: the areas' working distance.
  double wall_distance{std::numeric_limits<double>::quiet_NaN()};
  /// Output files per rectangle ("<stem>_<i>.json/.png"); empty: none.
  std::string output_stem;
};

struct SprayRunResult {
  AreaMap areas;
  std::vector<SerpentinePlan> plans;
  std::vector<SprayReport> reports;
  double max_tcp_error{0.0};   ///< largest distance of the true TCP from its target while spraying [m]
  double max_standoff_error{0.0};  ///< largest |true standoff - planned| while spraying [m]
  double sim_time{0.0};        ///< simulated seconds
  double wall_time{0.0};       ///< seconds of this machine
};

/// Runs the rectangles. Throws FinishError naming what failed (a refused path, a bad file).
SprayRunResult run_spray_in_sim(const SprayRunParams& params);

}  // namespace concert::surface_finish

#include "surface_finish/admittance.hpp"

namespace concert::surface_finish {

/// A sanding run in the MuJoCo simulator, without DDS: the sanding robot stands in front of the
/// world file's plaster panel (its first `surfaces` entry, bumps and holes rendered into a
/// MuJoCo height field by libs/sim), the areas are computed against the panel's nominal surface,
/// the serpentine is planned, and the arm is driven the way the robot service drives it for a
/// CartesianImpedanceCommand (tau = J^T (K (x_d - x) + D (v_d - v)) + g(q) - d_null qd, effort
/// mode) with the external wrench estimated from the joint torques as the robot service
/// estimates it (quasi-static J^T F = ID(q, qd, 0) - tau, damped least squares, 20 ms low-pass).
/// The ForceAdmittance law closes on that estimate every `command_period` and moves the
/// reference along z_ee; the simulator's true contact force on the tool is recorded alongside.
struct SandRunParams {
  std::filesystem::path assembly;                 ///< robot with a sanding tool
  std::vector<std::filesystem::path> module_dbs;  ///< module database folders
  std::filesystem::path world;                    ///< world file with the plaster panel
  std::string area{"centre"};                     ///< area id
  std::optional<Rect> rect;                       ///< reshaped rectangle inside it; none: the whole area
  ToolSpec tool{Task::kSand, 0.0, 0.23, 0.1};
  /// 0.1 m/s strokes, no settling hold, the approach from 5 cm at 5 cm/s.
  PathParams path{0.1, 0.5, 0.02, 0.05, 0.05, 0.0, 0.0, 0.8};
  AreaParams areas;
  double force{30.0};                             ///< setpoint [N]
  double tolerance{3.0};                          ///< band for the statistics [N]
  /// The law: 0.01 m/(N s) (a force loop of 15 /s on the 1.5 kN/m impedance), offsets up to 0.1 m.
  AdmittanceParams admittance{0.01, 0.0002, 2.0, 0.05, 0.1, 0.01};
  /// Cartesian impedance of the robot service's command: translation [N/m], rotation [N m/rad].
  double stiffness{1500.0}, rot_stiffness{150.0};
  double normal_stiffness{0.0};  ///< along z_ee [N/m]; 0: `stiffness`
  double damping_ratio{1.0};  ///< translational damping = 2 zeta sqrt(K m), m = 10 kg; rotation 2 zeta sqrt(K 0.5)
  double command_period{0.001};  ///< the admittance law's period (the command rate over DDS) [s]
  double start_delay{1.0};       ///< held in contact at the setpoint before the strokes (the user's start) [s]
  /// The run stops (leaves the wall) when the estimated force exceeds this [N]; NaN: 2 x force + 20.
  double abort_force{std::numeric_limits<double>::quiet_NaN()};
  double trace_period{0.005};    ///< [s]
  /// The true force is judged averaged over this window (the impulse the wall received per
  /// window). MuJoCo 2.2's per-step contact force on the sliding pad flickers: with the disc
  /// standing (friction 0.8-1.0) the contact is found in about 60 % of the steps, with ~50 N
  /// when it is and 0 when not, while the TCP stays within 0.01 mm of the wall (the same on a
  /// flat box: not the height field); with the disc running in about 96 %. No force sensor
  /// sees that. The raw per-step figures are reported too (SandRunResult::raw_*).
  double truth_window{0.1};      ///< [s]
  /// The running disc. The Sanding Tool is a commercial (drywall) sander with a 0.23 m disc:
  /// its abrasive slides on the plaster at the rim speed, so the friction against the stroke is
  /// the abrasive's friction scaled by (stroke speed) / (omega R) (uniform pressure, v << omega R:
  /// the mean of the sliding directions over the disc), about 0.007 at 1000 rpm and 0.1 m/s.
  /// MuJoCo's disc does not spin: its contact gets that friction (sim::SimParams::link_friction).
  /// With the disc standing (disc_rpm 0) it is a dry block dragged at abrasive_friction: on the
  /// plaster it sticks and slips (see the README's benchmark).
  double disc_rpm{1000.0};         ///< the disc's speed (estimated; drywall sanders run 600-1800 rpm); 0: standing
  double abrasive_friction{0.8};   ///< sandpaper on plaster, sliding friction (estimated) [-]
  /// "<stem>.json" (statistics), "<stem>.png" (Fig. 24 plot), "<stem>.csv" (the trace); empty: none
  std::string output_stem;
};

struct SandRunResult {
  AreaMap areas;
  SerpentinePlan plan;
  Rect rect;
  std::vector<ForceSample> trace;  ///< estimated (joint torques) and true (MuJoCo) force along z_ee
  ForceStats estimated;            ///< statistics of the estimate during the strokes
  ForceStats truth;                ///< of the simulator's contact force during the strokes
  double max_truth_error{0.0};     ///< largest |true force - setpoint| during the strokes [N]
  double truth_within_10{0.0};     ///< fraction of the stroke time the true force is within +-10 N (the paper's band)
  double raw_truth_mean{0.0}, raw_truth_std{0.0};  ///< per-step true force during the strokes [N]
  double contact_step_fraction{0.0};  ///< of the stroke steps with a contact on the tool
  double mean_abs_truth_error{0.0};
  double disc_friction{0.0};       ///< the friction the simulated disc's contact got (disc_rpm, abrasive_friction) [-]
  double max_offset{0.0};          ///< largest admittance offset [m]
  double max_lateral_error{0.0};   ///< largest in-plane TCP error during the strokes [m]
  std::string aborted;             ///< why the run left the wall early; empty: it did not
  double sim_time{0.0};
  double wall_time{0.0};
};

/// Runs the serpentine. Throws FinishError naming what failed (a refused path, a bad file).
SandRunResult run_sand_in_sim(const SandRunParams& params);

/// The statistics as JSON (N, mm, s, %).
std::string sand_report_json(const SandRunResult& result, const SandRunParams& params);

}  // namespace concert::surface_finish
