#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "nav/costmap.hpp"

namespace concert::nav {

/// A path of map-frame poses (x [m], y [m], theta [rad]).
using Path = std::vector<Eigen::Vector3d>;

/// Global planner parameters (nav2 Smac Planner 2D's meaning where they share a name).
struct PlannerParams {
  /// Weight of the cell cost in the traversal cost: a step of length d through a cell of cost
  /// c costs d * (1 + cost_penalty * c / 252).
  double cost_penalty{2.0};
  /// The robot centre keeps this much more than the inscribed radius from obstacles [m], so
  /// the footprint fits with room for tracking errors (cells of higher cost are not crossed,
  /// except within the circumscribed radius of start and goal).
  double clearance_margin{0.1};
  /// Cross cells the static map marks unknown (only when the costmap keeps them unknown).
  bool allow_unknown{false};
  /// Expansion budget of the A* search (0: unlimited).
  int max_expansions{2'000'000};
  /// Planning time budget [s of the planning thread's CPU time] (<= 0: unlimited).
  double max_planning_time{2.0};
  /// A start whose footprint covers an obstacle (a task left the base near a wall) is left by
  /// a straight move of up to this much, heading kept, that touches nothing new [m]; 0: refused.
  double escape_distance{0.5};
  /// Smooth the path (shortcuts that are not costlier, then gradient smoothing).
  bool smooth{true};
  /// Gradient smoother: iterations, weight of the original path and of the smoothness term.
  int smoother_iterations{100};
  double smoother_w_data{0.2};
  double smoother_w_smooth{0.3};
};

/// Why a plan failed (or kOk).
enum class PlanStatus : std::uint8_t {
  kOk,
  kStartOutsideMap,
  kStartInCollision,
  kGoalOutsideMap,
  kGoalInCollision,
  kGoalUnknown,
  kNoPath,
  kExpansionLimit,
  kTimeout,
};

/// Short name of a status ("start_in_collision", ...).
const char* to_string(PlanStatus status);

/// A plan: status, a message naming what failed and where, and on success the path.
struct PlanResult {
  PlanStatus status{PlanStatus::kNoPath};
  std::string message;      ///< empty on success
  Path path;                ///< from start to goal, spacing ~ the map resolution; last pose = goal
  double length{0.0};       ///< path length [m]
  int expansions{0};        ///< A* nodes expanded
  double search_time{0.0};  ///< A* search [s]
  double total_time{0.0};   ///< search + smoothing [s]
  [[nodiscard]] bool ok() const { return status == PlanStatus::kOk; }
};

/// Cost-aware A* on the costmap's cells, 8-connected, octile-distance heuristic (admissible:
/// every step costs at least its length), at the level of nav2's Smac Planner 2D: the robot
/// centre stays out of cells of cost >= kInscribed (except near start and goal, where the full
/// footprint is checked instead; clearance_margin adds to the inscribed radius), then the path is
/// shortened where a straight segment is not costlier than what it replaces, resampled at the map
/// resolution, smoothed, and given orientations: the direction of travel, the goal's heading at the
/// end.
///
/// Keeps its search buffers between calls (not thread-safe; one planner per thread).
class GlobalPlanner {
 public:
  /// Throws std::invalid_argument naming a bad parameter.
  explicit GlobalPlanner(const PlannerParams& params = {});

  /// Plans from `start` to `goal` (x [m], y [m], theta [rad], map frame) on `costmap`.
  PlanResult plan(const Costmap& costmap, const Eigen::Vector3d& start,
                  const Eigen::Vector3d& goal);

  [[nodiscard]] const PlannerParams& params() const { return params_; }

 private:
  PlannerParams params_;
  std::vector<float> g_;
  std::vector<std::int32_t> parent_;
  std::vector<std::uint32_t> visit_;  // generation stamp: g_/parent_ valid when == generation_
  std::vector<std::uint32_t> closed_;
  std::uint32_t generation_{0};
};

}  // namespace concert::nav
