#pragma once
// A sanding run through the robot service, as a sequence of what is commanded when (no DDS):
// the planned serpentine's joint-space part (the move to the approach pose, 5 cm off the wall)
// is one joint trajectory; from the approach pose on, Cartesian impedance targets of the
// plan's TCP with the robot service's admittance along the TCP's z (into the wall):
//
//   approach   along the plan to contact_gap in front of the nominal surface (impedance only)
//   contact    held at the first stroke's start, the force setpoint ramped from 0 (ramp_time),
//              then held (start_delay): the admittance closes the gap and meets the surface
//              under force control
//   strokes    the serpentine in contact, the force held by the admittance along z_ee, the
//              other directions under impedance
//   unload     held at the last stroke's end, the setpoint ramped back to 0 (unload_time)
//   retreat    admittance off, the plan's retreat off the wall
//
// The nominal surface is the wall the lidars fit, in their plane; a plaster layer or a panel
// above that plane stands proud of it by an unknown few millimetres. Every target in contact
// is therefore held contact_gap in front of the nominal surface and the admittance finds the
// real one: the impedance alone never pushes the disc into the plaster (on entering contact,
// nor when the admittance is switched off for the retreat).
//
// The time is the robot's (the stamps of its estimates). The force samples (the robot's
// estimate from the joint torques, the force pushed along z_ee) give the statistics of the
// stroke time and stop the run when far outside the band: above abort_force for abort_time, or
// (while stroking) below lost_contact_fraction x setpoint for lost_contact_time; the run then
// leaves the wall straight along the normal (leaving) and ends aborted.
//
// Leaving contact is part of every end in contact: a user's abort leaves the wall the same way
// (abort()); a safety stop holds the robot where it is (held), and the run leaves the wall once
// the stop is reset. The leave starts where the TCP is measured (set_tcp), not at the commanded
// target: with the admittance off, a target that the admittance had held inside the plaster
// would first push the disc into it.
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <optional>
#include <cstdint>
#include <string>
#include <vector>

#include "concert/model/robot_model.hpp"

#include "surface_finish/admittance.hpp"
#include "surface_finish/serpentine.hpp"

namespace concert::surface_finish {

struct SandParams {
  double force{30.0};       ///< setpoint [N]
  double tolerance{3.0};    ///< band of the statistics [N]
  double ramp_time{2.0};    ///< setpoint ramp from 0 in contact [s]
  double start_delay{1.0};  ///< held at the setpoint before the strokes [s]
  double unload_time{1.0};  ///< setpoint ramp back to 0 before the retreat [s]
  /// Admittance compliance of the robot service's law along z_ee [m/(N s)]: 0.01, the offline
  /// run's (a 15 /s force loop on the 1.5 kN/m impedance).
  double admittance_gain{0.01};
  /// Cartesian impedance: translation [N/m], rotation [N m/rad], critically damped (damping
  /// ratio) for 10 kg and 0.5 kg m^2, as the offline run (SandRunParams).
  double stiffness{1500.0}, rot_stiffness{150.0}, damping_ratio{1.0};
  /// Stop: the estimate above this for abort_time [N]; NaN: 2 x force + 20 N.
  double abort_force{std::numeric_limits<double>::quiet_NaN()};
  double abort_time{0.05};             ///< [s]
  double lost_contact_fraction{0.25};  ///< of the setpoint, while stroking
  double lost_contact_time{1.0};       ///< [s]
  double leave_time{1.0};  ///< after a stop: back off the wall by the plan's approach over this [s]
  /// The Cartesian targets in contact stay this far in front of the nominal surface; the
  /// admittance closes the gap [m]. A surface up to this much proud of the fitted wall is met
  /// under force control. Less than the plan's approach.
  double contact_gap{0.02};
};

enum class SandPhase {
  kMove,
  kApproach,
  kContact,
  kStrokes,
  kUnload,
  kRetreat,
  kLeaving,
  kHeld,  ///< a safety stop in contact: the robot holds; the run leaves the wall after the reset
  kDone,
  kAborted
};

const char* to_string(SandPhase phase);

/// What to command the robot now (Cartesian impedance of the TCP, base frame).
struct SandCommand {
  Eigen::Isometry3d target{Eigen::Isometry3d::Identity()};
  Eigen::Vector3d velocity{0.0, 0.0, 0.0};  ///< the path's TCP velocity [m/s]
  std::array<double, 6> stiffness{};
  std::array<double, 6> damping{};
  bool admittance{false};      ///< along the TCP's z (into the wall)
  double force_setpoint{0.0};  ///< [N], pushed along z_ee
  double admittance_gain{0.0};
};

class SandSequence {
 public:
  /// Throws FinishError for a force <= 0 or not finite, bad parameters, or a plan without
  /// approach pose or stroke (`approach`: the plan's PathParams::approach).
  SandSequence(SerpentinePlan plan, SandParams params);

  [[nodiscard]] const SerpentinePlan& plan() const { return plan_; }
  [[nodiscard]] const SandParams& params() const { return params_; }
  /// The plan's samples [0, approach_index()] are the joint move to the approach pose.
  [[nodiscard]] std::size_t approach_index() const { return i_app_; }
  /// The TCP's z (into the wall), base frame.
  [[nodiscard]] const Eigen::Vector3d& normal() const { return z_ee_; }

  /// The arm is at the approach pose at robot time t [s]: the Cartesian phases begin.
  void start(double t);
  /// Advances the phases to robot time t and returns what to command (valid from kApproach to
  /// kLeaving; kMove: the joint trajectory runs, nothing else).
  SandCommand update(double t);
  /// One estimate sample: the force pushed along z_ee at robot time t [N]. Recorded (stroke
  /// samples give the statistics), checked against the stop limits.
  void add_force(double t, double pushed);
  /// Stops now without moving (the robot's refusal, a new model, the service stopping): kAborted.
  void stop(const std::string& reason);
  /// A user's abort: in the Cartesian phases the tool leaves the wall along the normal first
  /// (kLeaving, then kAborted with `reason`); during the joint move it stops at once. True when
  /// it leaves (the run ends when update() reaches kAborted).
  bool abort(const std::string& reason);
  /// A safety stop (`reason`): in the Cartesian phases or leaving, the run is held (kHeld: the
  /// robot holds the tool where it is) until resume_leaving(); before them it stops at once.
  void hold_for_safety(const std::string& reason);
  /// The safety stop is reset at robot time t [s]: a held run leaves the wall from there.
  void resume_leaving(double t);
  /// The TCP as measured now (base frame): where a leave starts.
  void set_tcp(const Eigen::Isometry3d& tcp) { measured_tcp_ = tcp; }

  [[nodiscard]] SandPhase phase() const { return phase_; }
  [[nodiscard]] bool finished() const {
    return phase_ == SandPhase::kDone || phase_ == SandPhase::kAborted;
  }
  [[nodiscard]] const std::string& reason() const { return reason_; }
  /// Executed fraction of the plan's time (0 during the joint move) [0, 1].
  [[nodiscard]] double progress() const;
  /// Sets the joint move's progress (the robot's trajectory status) [0, 1].
  void set_move_progress(double p) { move_progress_ = p; }
  [[nodiscard]] const std::vector<ForceSample>& trace() const { return trace_; }
  /// The statistics of the stroke samples; throws FinishError when there is none.
  [[nodiscard]] ForceStats stats() const;
  /// JSON of the run (state, reason, plan, statistics in N, s, %).
  [[nodiscard]] std::string report_json() const;

 private:
  [[nodiscard]] double abort_force() const;
  [[nodiscard]] const PathSample& at(double plan_t, Eigen::Vector3d& p, Eigen::Vector3d& v) const;
  [[nodiscard]] bool stroking(double t) const;
  void leave(const std::string& reason);

  SerpentinePlan plan_;
  SandParams params_;
  std::size_t i_app_{0}, i_wall_{0}, i_last_{0};
  Eigen::Vector3d z_ee_{0.0, 0.0, 1.0};
  SandPhase phase_{SandPhase::kMove};
  double phase_start_{0.0};  // robot time the phase began
  double now_{0.0};
  double plan_t_{0.0};
  double move_progress_{0.0};
  double over_since_{-1.0}, under_since_{-1.0};
  Eigen::Isometry3d leave_from_{Eigen::Isometry3d::Identity()};
  std::optional<Eigen::Isometry3d> measured_tcp_;
  SandCommand last_;
  std::string reason_;
  std::vector<ForceSample> trace_;
};

/// The joint move to the approach pose as the robot reports its trajectory.
enum class MoveReport { kNoAnswer, kRunning, kSucceeded, kStopped };

/// One control cycle of a sanding run as the service measured it.
struct SandCycle {
  /// The safety layer's causes ("e-stop: software") when it is not RUNNING; none while it runs.
  std::optional<std::string> safety_stop;
  MoveReport move{MoveReport::kNoAnswer};
  double move_progress{0.0};  ///< the trajectory's progress [0, 1] (when answered)
  std::string move_reason;    ///< kStopped: the robot's reason
  double since_sent{0.0};     ///< [s] since the move's trajectory was sent
  double silence{0.0};        ///< [s] without a force estimate from the robot, up to now
  struct Force {
    double t{0.0};                              ///< robot time [s]
    Eigen::Vector3d force{0.0, 0.0, 0.0};       ///< the estimate at the TCP, base axes [N]
  };
  std::vector<Force> forces;  ///< the estimates since the last cycle, oldest first
  std::optional<Eigen::Isometry3d> tcp;  ///< the TCP measured now (base frame), when known
};

/// How long the supervision waits.
struct SandWatch {
  double wrench_timeout{2.0};        ///< [s] without a force estimate: the run is aborted
  double move_answer_timeout{10.0};  ///< [s] for the robot to answer the move's trajectory
};

/// How a cycle ends the run, if it does.
enum class SandEnd { kNone, kSucceeded, kFailed, kAborted };

/// What one cycle asks the service to do.
struct SandStep {
  std::optional<SandCommand> command;  ///< the arm's Cartesian impedance command to send
  SandEnd end{SandEnd::kNone};
  std::string reason;  ///< kFailed, kAborted: why
};

/// One cycle of a run: a safety stop aborts it during the joint move and holds it (kHeld) in
/// contact, the run leaving the wall once the stop is reset; during the joint move, the robot's answer
/// starts the Cartesian phases (at the robot time of the newest estimate), or its refusal, or
/// its silence, fails the run; afterwards every estimate is fed to `seq` (the force pushed along
/// its z_ee) and the newest one's command returned, and a silent force estimate aborts the run.
SandStep supervise(SandSequence& seq, const SandCycle& cycle, const SandWatch& watch);

/// A new robot model while a run is on: what the service knows of it.
struct NewModel {
  std::uint32_t version{0};
  const model::RobotModel* before{nullptr};  ///< the run's model
  const model::RobotModel* after{nullptr};   ///< the new one; null when it did not build
  std::string error;                         ///< why it did not build
  std::string tcp_frame;                     ///< the run's tool frame
  std::vector<std::string> names;            ///< the joints measured now (none yet: empty)
  std::vector<double> positions;
};

/// A new model during a run: the tool leaves the wall under the new version (as on a user's
/// abort) when the new model puts it where the run's model does at the joints measured now
/// (model::same_frame_pose: the same arm, a module swapped elsewhere); otherwise the run stops
/// where it is and the arm holds, because another arm's joints no longer say where the tool is.
/// Returns true when the run leaves (command it at the new version until it ends); `seq`'s
/// reason names the version and, when the arm holds, why.
bool leave_for_new_model(SandSequence& seq, const NewModel& m);

}  // namespace concert::surface_finish
