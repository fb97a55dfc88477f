#pragma once
// A simulated person's hand on the robot, for collaborative transport (paper sections 5.5-5.6)
// in simulation: a spring-damper from the hand to one link of the robot (the gripper's TCP). The
// hand guides the link (teaching), holds still, or walks a route at walking speed (follow-me),
// waiting while the robot lags and letting go when it falls too far behind or when asked.
//
// Pure Eigen, no MuJoCo: whoever runs the physics asks force() once a physics step and applies
// it to the link (SimHardware::set_external_force). Time is the simulation's: a loaded machine
// slows the walk with the robot, it never outruns it.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace concert::world {

struct PersonParams {
  double stiffness{150.0};     ///< the person's arm: spring [N/m]
  double damping{30.0};        ///< and damper [N s/m]
  double speed{0.5};           ///< walking speed [m/s]
  double ramp{1.0};            ///< [s] from standing to walking speed
  double wait_stretch{0.6};    ///< [m] the hand this far from the link (in the plane): the person waits
  double let_go_stretch{1.0};  ///< [m] this far: the person lets go (150 N at the default spring)
  double arrive_radius{0.15};  ///< [m] the link this near the route's end ...
  double arrive_time{1.0};     ///< [s] ... this long: arrived
};

/// Throws std::invalid_argument naming the first bad field ("person: wait_stretch: expected a
/// number in (0, let_go_stretch = 1), got 1.2").
void check(const PersonParams& p);

enum class PersonPhase {
  kAbsent,   ///< not holding anything
  kGuiding,  ///< gripping, the hand moving the link by the guide
  kHolding,  ///< gripping, the hand still
  kWalking,  ///< walking the route
  kWaiting,  ///< on the route, standing: the link lags more than wait_stretch
  kArrived,  ///< at the route's end, the link there for arrive_time; still gripping
  kLetGo     ///< let go (reason() says why); no force
};
const char* to_string(PersonPhase phase);

class SimPerson {
 public:
  explicit SimPerson(PersonParams params = {});

  /// Grips the link, which is at `tcp` (world) at time `t` [s], and guides it by `guide` (world)
  /// over `guide_time` [s], then holds it there. guide_time <= 0: holds at once.
  void grip(double t, const Eigen::Vector3d& tcp, const Eigen::Vector3d& guide = Eigen::Vector3d::Zero(),
            double guide_time = 0.0);
  /// Walks from where the hand is through `route` (world x, y; the hand's height kept) at walking
  /// speed. Throws std::logic_error when not gripping, std::invalid_argument for an empty route.
  void walk(double t, std::vector<Eigen::Vector2d> route);
  /// Lets go (no force from now on); `reason` says why.
  void let_go(std::string reason);

  /// The force on the link [N, world] for the physics step that ends at `t` [s], the link at
  /// `tcp` moving at `tcp_velocity` (world). Advances the hand. Zero while not gripping.
  Eigen::Vector3d force(double t, const Eigen::Vector3d& tcp, const Eigen::Vector3d& tcp_velocity);

  [[nodiscard]] PersonPhase phase() const { return phase_; }
  [[nodiscard]] bool gripping() const;
  [[nodiscard]] const std::string& reason() const { return reason_; }
  [[nodiscard]] const Eigen::Vector3d& hand() const { return hand_; }
  /// Along the route [m], and its length.
  [[nodiscard]] double walked() const { return walked_; }
  [[nodiscard]] double route_length() const;
  /// The largest pull since the last grip [N].
  [[nodiscard]] double peak_pull() const { return peak_pull_; }
  /// The pull of the last step [N, world].
  [[nodiscard]] const Eigen::Vector3d& pull() const { return pull_; }

 private:
  [[nodiscard]] Eigen::Vector2d route_at(double s) const;
  void step_guide(double t);
  void step_walk(double dt, const Eigen::Vector3d& tcp);

  PersonParams params_;
  PersonPhase phase_{PersonPhase::kAbsent};
  std::string reason_;
  double last_t_{0.0};
  Eigen::Vector3d hand_{Eigen::Vector3d::Zero()};
  Eigen::Vector3d hand_velocity_{Eigen::Vector3d::Zero()};
  Eigen::Vector3d pull_{Eigen::Vector3d::Zero()};
  double peak_pull_{0.0};
  // Guiding.
  Eigen::Vector3d guide_from_{Eigen::Vector3d::Zero()}, guide_{Eigen::Vector3d::Zero()};
  double guide_start_{0.0}, guide_time_{0.0};
  // Walking: the route's points (the hand's start first) and their distances along it.
  std::vector<Eigen::Vector2d> route_;
  std::vector<double> along_;
  double walked_{0.0};
  double moving_for_{0.0};  // [s] since the person last started walking (the ramp)
  double arrived_for_{0.0};
};

}  // namespace concert::world
