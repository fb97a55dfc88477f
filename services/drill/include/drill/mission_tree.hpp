#pragma once
// The drilling mission as a behaviour tree (paper Fig. 11): initialise -> per area in FIFO
// order: navigate if the area has a base pose -> execute the approach (planned while the
// previous area was drilled) -> detect the points -> survey which of them the robot can reach
// (not in the paper: those it cannot are reported, not attempted) -> place the base once for them
// (not in the paper: drill/placement.hpp says why) -> per point: align, drill, retract; then the arm home
// (not in the paper: navigation and a tool swap start from the transport posture).
// Plain C++, no DDS.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "drill/mission.hpp"
#include "drill/ports.hpp"

namespace concert::drill {

/// What happened to one hole.
enum class HoleState { kPending, kDrilled, kFailed, kSkipped };
/// What happened to one area.
enum class AreaState { kPending, kActive, kDone, kFailed, kSkipped };
/// The mission as a whole.
enum class MissionState { kIdle, kRunning, kSucceeded, kFailed, kAborted };

/// HoleReport::reason of a hole that resume() found drilled by a previous run (kSkipped).
inline constexpr const char* kDrilledBefore = "drilled in a previous run";
/// AreaReport::reason of an area that resume() found done by a previous run (kSkipped).
inline constexpr const char* kDoneBefore = "done in a previous run";

const char* to_string(HoleState s);
const char* to_string(AreaState s);
const char* to_string(MissionState s);

/// Where one hole's time went [s of the clock given to tick()]: `align` is everything from the
/// hole's start to the bit aligned in front of it (its posture planned and reached, the looks at
/// its mark, the alignment), `drill` the feed into the wall, `retract` the way back out and onto
/// the area's postures.
struct HoleTimes {
  double align{0.0};
  double drill{0.0};
  double retract{0.0};
};

/// Where one area's own time went [s]: `approach` navigating to it, waiting for its approach
/// plan and executing it; `detect` finding its marks; `survey` judging its holes' reach; `place`
/// placing the base for them. Its holes' times are theirs.
struct AreaTimes {
  double approach{0.0};
  double detect{0.0};
  double survey{0.0};
  double place{0.0};
};

struct HoleReport {
  DrillPoint point;
  HoleState state{HoleState::kPending};
  std::string reason;  ///< why it failed or was skipped
  HoleReach reach;     ///< the survey's verdict before anything moved for it (unknown until then)
  HoleTimes times;
};

struct AreaReport {
  std::string name;
  AreaState state{AreaState::kPending};
  std::string reason;
  ResolvedArea located;
  std::vector<HoleReport> holes;  ///< once detected
  AreaTimes times;
};

/// Time spent in each kind of work [s of the clock given to tick()]: navigate, plan (only the
/// part the mission waited for), execute (approach trajectories), drill (align + drill +
/// retract + detect).
struct MissionTimes {
  double navigate{0.0};
  double plan{0.0};
  double execute{0.0};
  double drill{0.0};
  double total{0.0};
};

struct MissionReport {
  std::string mission;
  MissionState state{MissionState::kIdle};
  std::string reason;  ///< why it failed or was aborted
  std::vector<AreaReport> areas;
  MissionTimes times;
  [[nodiscard]] int holes_drilled() const;
  /// Detected points (pending + drilled + failed + skipped).
  [[nodiscard]] int holes_marked() const;
};

/// What the tree is doing now.
struct MissionStatus {
  MissionState state{MissionState::kIdle};
  /// Path of the active node from the root, e.g. "mission/area 'a2'/hole 'blob 1'/drill".
  std::string active;
  std::size_t area{0};  ///< index of the current area
  std::size_t hole{0};  ///< index of the current hole in it
  std::string reason;
};

/// Runs one mission on a MissionPorts, one tick at a time.
///
/// Bad input in an area (unknown wall, unreachable area, marker without a pattern, no blob
/// where one was expected) fails that area with its reason and the mission goes on with the
/// next area; a failed hole goes on with the next hole after retracting. health() failing
/// (e-stop, lost service) stops every motion and ends the mission kAborted, as abort() does.
/// After the last area the arm goes home (MissionPorts::stow); a homing that fails fails the
/// mission with its reason, the holes' states as they are.
/// A new tree built with resume() skips every hole a previous report drilled.
class MissionTree {
 public:
  MissionTree(Mission mission, MissionPorts& ports);
  ~MissionTree();
  MissionTree(const MissionTree&) = delete;
  MissionTree& operator=(const MissionTree&) = delete;

  /// Continues from a previous run of the same mission: its drilled holes are not drilled
  /// again (matched by area name and hole position within 1 cm), its done areas are skipped.
  void resume(const MissionReport& previous);

  /// Advances the tree; `now` is a monotonic clock [s]. Returns the mission state after it.
  MissionState tick(double now);
  /// Stops every motion (MissionPorts::stop) and ends the mission kAborted with `reason`.
  void abort(const std::string& reason);

  [[nodiscard]] MissionStatus status() const;
  [[nodiscard]] const MissionReport& report() const;
  /// The tree's shape, one node a line, indented (the tests print it).
  [[nodiscard]] std::string describe() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace concert::drill
