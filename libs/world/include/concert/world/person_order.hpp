#pragma once
// What the simulated person (person.hpp) is told over the simulator's command channel
// (SimCommand SIM_PERSON, `concert sim person ...`), and what it reports back: a YAML text each
// way, so that it travels as the assembly and world YAML do.
//
// The order (every key but `action` optional):
//
//   action: grip            # grip | walk | release | status
//   link: tcp_E             # grip: the body held; absent: the mounted robot's gripper TCP
//   guide: [0.1, 0, -0.1]   # grip: the hand moves the link by this [m, world] ...
//   guide_time: 2.0         # ... over this [s]; 0: the hand holds still
//   stiffness: 150          # grip: PersonParams' fields (person.hpp)
//   route: [-3.0, 0.0]      # walk: x, y pairs [m] ...
//   relative: true          # ... offsets from the hand where the walk starts (false: the world's)

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "concert/world/person.hpp"

namespace concert::world {

struct PersonOrder {
  enum class Action { kGrip, kWalk, kRelease };
  Action action{Action::kGrip};
  std::string link;                                ///< grip: "" = the mounted robot's gripper TCP
  Eigen::Vector3d guide{Eigen::Vector3d::Zero()};  ///< grip [m, world]
  double guide_time{0.0};                          ///< [s] of simulated time
  std::vector<Eigen::Vector2d> route;              ///< walk: x, y [m]
  bool relative{true};
  PersonParams params;  ///< grip: the person's arm and walk
};

/// The person after a physics step.
struct PersonReport {
  PersonPhase phase{PersonPhase::kAbsent};
  std::string link;    ///< the body held or last held
  std::string reason;  ///< why it let go
  Eigen::Vector3d hand{Eigen::Vector3d::Zero()};  ///< the person's hand (world) [m]
  Eigen::Vector3d tcp{Eigen::Vector3d::Zero()};   ///< the link held or last held, where it is now (world) [m]
  Eigen::Vector3d pull{Eigen::Vector3d::Zero()};  ///< the person's force on it [N]
  double walked{0.0}, route_length{0.0}, peak_pull{0.0};
  double time{0.0};          ///< simulated time [s]
  std::uint64_t orders{0};   ///< orders taken so far
};

/// The order in `yaml` (`source` names it in errors); nullopt for `action: status`. Throws
/// std::invalid_argument naming the source, the key and its line.
std::optional<PersonOrder> parse_person_order(const std::string& yaml, const std::string& source);
/// The order as YAML, as parse_person_order() reads it back (the command line writes it so).
std::string person_order_yaml(const PersonOrder& order);
/// A report as one line of YAML (a flow mapping):
/// {phase: walking, link: tcp_E, walked: 1.23, route_length: 3, pull: 48.1, peak_pull: 62, ...}
std::string person_report_yaml(const PersonReport& report);
/// Reads a report back from person_report_yaml()'s text; throws std::invalid_argument.
PersonReport parse_person_report(const std::string& yaml);
/// The phase named by to_string(PersonPhase); throws std::invalid_argument.
PersonPhase person_phase(const std::string& name);

}  // namespace concert::world
