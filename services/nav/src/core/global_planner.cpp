#include "nav/global_planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "concert/common/thread_cpu_clock.hpp"
#include "grid_line.hpp"
#include "pose_text.hpp"

namespace concert::nav {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct QueueEntry {
  float f;
  float g;
  std::int32_t index;
};

// Min-heap on f; on equal f the deeper node (larger g) first.
bool later(const QueueEntry& a, const QueueEntry& b) {
  return a.f > b.f || (a.f == b.f && a.g < b.g);
}

// What the search and the smoother may cross: cells the robot centre can occupy.
class Traversability {
 public:
  Traversability(const Costmap& map, const PlannerParams& params, const Eigen::Vector2d& start,
                 const Eigen::Vector2d& goal)
      : map_(map), params_(params), start_(start), goal_(goal) {
    const double r = map.shape().circumscribed_radius;
    escape2_ = r * r;
    // Costs at or above the cost at inscribed radius + margin are too close; with an
    // inflation radius short of that, the inscribed cost is the only bound.
    const std::uint8_t bound =
        map.inflation_cost(map.shape().inscribed_radius + params.clearance_margin);
    too_close_ = bound > Costmap::kFree ? bound : Costmap::kInscribed;
  }

  [[nodiscard]] bool valid(int col, int row) const {
    const std::uint8_t c = map_.cost(col, row);
    if (c < too_close_) return true;
    if (c == Costmap::kLethal) return false;
    if (c == Costmap::kNoInformation) return params_.allow_unknown;
    // Too close to an obstacle: only where the robot starts or stops, whose full footprints
    // were checked.
    const Eigen::Vector2d p = map_.center_of(col, row);
    return (p - start_).squaredNorm() <= escape2_ || (p - goal_).squaredNorm() <= escape2_;
  }

  /// Multiplier of a step's length through a cell: 1 + penalty * normalised cost.
  [[nodiscard]] float step_weight(std::uint8_t cost) const {
    const double c = std::min<double>(cost, Costmap::kInscribed - 1);
    return static_cast<float>(1.0 + params_.cost_penalty * c / (Costmap::kInscribed - 1));
  }

 private:
  const Costmap& map_;
  const PlannerParams& params_;
  Eigen::Vector2d start_;
  Eigen::Vector2d goal_;
  double escape2_;
  std::uint8_t too_close_;
};

// Keeps the points a straight segment may join without crossing an untraversable cell and
// without costing more (the search's traversal cost) than the stretch of path it replaces;
// `g` holds the search's cost-to-come of each point [cells].
std::vector<Eigen::Vector2d> shortcut(const Costmap& map, const Traversability& trav,
                                      const std::vector<Eigen::Vector2d>& pts,
                                      const std::vector<float>& g) {
  const double diag = std::sqrt(2.0);
  std::vector<Eigen::Vector2d> out{pts.front()};
  std::size_t anchor = 0;
  while (anchor + 1 < pts.size()) {
    std::size_t best = anchor + 1;
    const Eigen::Vector2i ca = map.cell_of(pts[anchor]);
    for (std::size_t j = anchor + 2; j < pts.size(); ++j) {
      const Eigen::Vector2i cj = map.cell_of(pts[j]);
      const double budget = static_cast<double>(g[j] - g[anchor]) + 1e-3;
      double cost = 0.0;
      Eigen::Vector2i prev = ca;
      const bool clear = detail::trace_line(ca.x(), ca.y(), cj.x(), cj.y(), [&](int c, int r) {
        if (!trav.valid(c, r)) return false;
        if (c != ca.x() || r != ca.y()) {
          const double step = (c != prev.x() && r != prev.y()) ? diag : 1.0;
          cost += step * trav.step_weight(map.cost(c, r));
          prev = {c, r};
        }
        return cost <= budget;
      });
      if (!clear) break;
      best = j;
    }
    out.push_back(pts[best]);
    anchor = best;
  }
  return out;
}

std::vector<Eigen::Vector2d> resample(const std::vector<Eigen::Vector2d>& pts, double spacing) {
  std::vector<Eigen::Vector2d> out{pts.front()};
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const Eigen::Vector2d a = pts[i - 1];
    const Eigen::Vector2d d = pts[i] - a;
    const double len = d.norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    for (int k = 1; k <= steps; ++k) out.push_back(a + d * (static_cast<double>(k) / steps));
  }
  return out;
}

// Gradient smoothing (nav2's simple smoother): each inner point moves towards its neighbours'
// midpoint and back towards where it was, unless that takes it into a costlier cell.
void smooth(const Costmap& map, const Traversability& trav, const PlannerParams& params,
            std::vector<Eigen::Vector2d>& pts) {
  if (pts.size() < 3) return;
  const std::vector<Eigen::Vector2d> original = pts;
  for (int it = 0; it < params.smoother_iterations; ++it) {
    for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
      const Eigen::Vector2d moved =
          pts[i] + params.smoother_w_data * (original[i] - pts[i]) +
          params.smoother_w_smooth * (pts[i - 1] + pts[i + 1] - 2.0 * pts[i]);
      const Eigen::Vector2i c = map.cell_of(moved);
      if (!map.inside(c.x(), c.y()) || !trav.valid(c.x(), c.y())) continue;
      const std::uint8_t allowed = std::max(map.cost_at(pts[i]), map.cost_at(original[i]));
      if (map.cost(c.x(), c.y()) <= allowed) pts[i] = moved;
    }
  }
}

}  // namespace

const char* to_string(PlanStatus status) {
  switch (status) {
    case PlanStatus::kOk:
      return "ok";
    case PlanStatus::kStartOutsideMap:
      return "start_outside_map";
    case PlanStatus::kStartInCollision:
      return "start_in_collision";
    case PlanStatus::kGoalOutsideMap:
      return "goal_outside_map";
    case PlanStatus::kGoalInCollision:
      return "goal_in_collision";
    case PlanStatus::kGoalUnknown:
      return "goal_unknown";
    case PlanStatus::kNoPath:
      return "no_path";
    case PlanStatus::kExpansionLimit:
      return "expansion_limit";
    case PlanStatus::kTimeout:
      return "timeout";
  }
  return "?";
}

GlobalPlanner::GlobalPlanner(const PlannerParams& params) : params_(params) {
  if (!(params_.clearance_margin >= 0.0)) {
    throw std::invalid_argument("global planner: clearance_margin " +
                                std::to_string(params_.clearance_margin) + " m: must be >= 0");
  }
  if (!(params_.cost_penalty >= 0.0)) {
    throw std::invalid_argument("global planner: cost_penalty " +
                                std::to_string(params_.cost_penalty) + ": must be >= 0");
  }
  if (params_.max_expansions < 0) {
    throw std::invalid_argument("global planner: max_expansions " +
                                std::to_string(params_.max_expansions) + ": must be >= 0");
  }
  if (params_.smoother_iterations < 0 || !(params_.smoother_w_data >= 0.0) ||
      !(params_.smoother_w_smooth >= 0.0) ||
      params_.smoother_w_data + 2.0 * params_.smoother_w_smooth >= 1.0) {
    throw std::invalid_argument(
        "global planner: smoother iterations >= 0 and weights w_data, w_smooth >= 0 with "
        "w_data + 2 w_smooth < 1 required (got " +
        std::to_string(params_.smoother_iterations) + ", " +
        std::to_string(params_.smoother_w_data) + ", " + std::to_string(params_.smoother_w_smooth) +
        ")");
  }
}

namespace {

// The nearest pose, heading kept, within `reach` [m] of `start` in one of 16 directions where the
// footprint is free at any heading, every pose on the way there (checked each half cell) going
// no deeper into an obstacle than Costmap::leaving_depth allows.
std::optional<Eigen::Vector3d> escape_pose(const Costmap& map, const Eigen::Vector3d& start, double reach) {
  // Only a footprint whose rim covers an obstacle leaves: a centre in one is no place to stand.
  if (!(reach > 0.0) || map.cost_at(start.head<2>()) >= Costmap::kLethal) return std::nullopt;
  const double allowed = map.leaving_depth(start);
  const double step = 0.5 * map.resolution();
  constexpr int kDirections = 16;
  std::vector<bool> blocked(kDirections, false);
  for (double d = step; d <= reach + 1e-9; d += step) {
    for (int k = 0; k < kDirections; ++k) {
      if (blocked[k]) continue;
      const double a = 2.0 * std::numbers::pi * k / kDirections;
      const Eigen::Vector3d pose(start.x() + d * std::cos(a), start.y() + d * std::sin(a), start.z());
      if (map.lethal_depth(pose) > allowed) {
        blocked[k] = true;  // it would go deeper on the way
        continue;
      }
      if (map.free_at_any_heading(pose.head<2>())) return pose;  // the path may turn from there
    }
  }
  return std::nullopt;
}

}  // namespace

PlanResult GlobalPlanner::plan(const Costmap& map, const Eigen::Vector3d& start,
                               const Eigen::Vector3d& goal) {
  const Clock::time_point t0 = Clock::now();
  // The budget is CPU time of this thread: a loaded machine makes the search slower, not shorter.
  const ThreadCpuClock::time_point cpu0 = ThreadCpuClock::now();
  PlanResult result;
  auto fail = [&](PlanStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.total_time = seconds_since(t0);
    return result;
  };
  const Eigen::Vector2i g = map.cell_of(goal.head<2>());
  if (!start.allFinite() || !map.inside(map.cell_of(start.head<2>()).x(), map.cell_of(start.head<2>()).y())) {
    return fail(PlanStatus::kStartOutsideMap,
                "start " + detail::pose_text(start) + " is outside the map");
  }
  // A start the footprint check refuses (a task left the base near a wall: the footprint is the
  // hull of the steering sweep and the transport posture): the path begins with the shortest
  // straight move, heading kept, that frees the footprint without touching a cell it does not
  // touch already.
  Path escape;
  Eigen::Vector3d from = start;
  if (map.in_collision(start)) {
    const std::optional<Eigen::Vector3d> free = escape_pose(map, start, params_.escape_distance);
    if (!free) {
      char b[96];
      std::snprintf(b, sizeof b, "; no straight move of up to %.2f m frees it", params_.escape_distance);
      return fail(PlanStatus::kStartInCollision,
                  "start " + detail::pose_text(start) + ": the robot's footprint there covers an obstacle" + b);
    }
    from = *free;
    const double distance = (from - start).head<2>().norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(distance / map.resolution())));
    for (int k = 0; k < steps; ++k) escape.push_back(start + (from - start) * (static_cast<double>(k) / steps));
    result.length += distance;
  }
  const Eigen::Vector2i s = map.cell_of(from.head<2>());
  if (!goal.allFinite() || !map.inside(g.x(), g.y())) {
    return fail(PlanStatus::kGoalOutsideMap,
                "goal " + detail::pose_text(goal) + " is outside the map");
  }
  if (map.unknown(g.x(), g.y()) && !(params_.allow_unknown && !map.params().unknown_is_lethal)) {
    return fail(PlanStatus::kGoalUnknown,
                "goal " + detail::pose_text(goal) + " lies in unknown space of the map");
  }
  if (map.in_collision(goal)) {
    return fail(
        PlanStatus::kGoalInCollision,
        "goal " + detail::pose_text(goal) + ": the robot's footprint there covers an obstacle");
  }

  const Traversability trav(map, params_, from.head<2>(), goal.head<2>());
  const std::size_t n =
      static_cast<std::size_t>(map.width()) * static_cast<std::size_t>(map.height());
  if (g_.size() != n) {
    g_.assign(n, 0.0f);
    parent_.assign(n, -1);
    visit_.assign(n, 0);
    closed_.assign(n, 0);
    generation_ = 0;
  }
  if (++generation_ == 0) {  // stamps wrapped: start afresh
    std::fill(visit_.begin(), visit_.end(), 0);
    std::fill(closed_.begin(), closed_.end(), 0);
    generation_ = 1;
  }
  const std::uint32_t gen = generation_;
  const int w = map.width();
  const auto start_i = static_cast<std::int32_t>(map.index(s.x(), s.y()));
  const auto goal_i = static_cast<std::int32_t>(map.index(g.x(), g.y()));
  const float diag = static_cast<float>(std::sqrt(2.0));
  auto heuristic = [&](int col, int row) {
    const float dx = static_cast<float>(std::abs(col - g.x()));
    const float dy = static_cast<float>(std::abs(row - g.y()));
    return std::max(dx, dy) + (diag - 1.0f) * std::min(dx, dy);
  };
  std::vector<QueueEntry> open;
  open.reserve(4096);
  g_[start_i] = 0.0f;
  parent_[start_i] = -1;
  visit_[start_i] = gen;
  open.push_back({heuristic(s.x(), s.y()), 0.0f, start_i});
  static constexpr int kDc[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static constexpr int kDr[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  bool found = false;
  while (!open.empty()) {
    std::pop_heap(open.begin(), open.end(), later);
    const QueueEntry top = open.back();
    open.pop_back();
    if (closed_[top.index] == gen || top.g > g_[top.index]) continue;
    closed_[top.index] = gen;
    ++result.expansions;
    if (top.index == goal_i) {
      found = true;
      break;
    }
    if (params_.max_expansions > 0 && result.expansions >= params_.max_expansions) {
      result.search_time = seconds_since(t0);
      return fail(PlanStatus::kExpansionLimit,
                  "no path from " + detail::pose_text(start) + " to " + detail::pose_text(goal) +
                      " within the budget of " + std::to_string(params_.max_expansions) +
                      " expansions");
    }
    if ((result.expansions & 1023) == 0 && params_.max_planning_time > 0.0 &&
        cpu_seconds_since(cpu0) > params_.max_planning_time) {
      result.search_time = seconds_since(t0);
      return fail(PlanStatus::kTimeout, "no path from " + detail::pose_text(start) + " to " +
                                            detail::pose_text(goal) +
                                            " within the planning time of " +
                                            std::to_string(params_.max_planning_time) + " s of CPU");
    }
    const int col = top.index % w;
    const int row = top.index / w;
    for (int k = 0; k < 8; ++k) {
      const int nc = col + kDc[k];
      const int nr = row + kDr[k];
      if (!map.inside(nc, nr)) continue;
      const auto ni = static_cast<std::int32_t>(map.index(nc, nr));
      if (closed_[ni] == gen || !trav.valid(nc, nr)) continue;
      if (k >= 4 && (!trav.valid(nc, row) || !trav.valid(col, nr))) continue;  // no corner cutting
      const float step = (k < 4 ? 1.0f : diag) * trav.step_weight(map.cost(nc, nr));
      const float ng = top.g + step;
      if (visit_[ni] == gen && ng >= g_[ni]) continue;
      visit_[ni] = gen;
      g_[ni] = ng;
      parent_[ni] = top.index;
      open.push_back({ng + heuristic(nc, nr), ng, ni});
      std::push_heap(open.begin(), open.end(), later);
    }
  }
  result.search_time = seconds_since(t0);
  if (!found) {
    return fail(PlanStatus::kNoPath,
                "no path from " + detail::pose_text(start) + " to " + detail::pose_text(goal) +
                    ": the goal is not connected to the start through free space (" +
                    std::to_string(result.expansions) + " cells searched)");
  }

  std::vector<Eigen::Vector2d> pts;
  std::vector<float> cost_to_come;
  for (std::int32_t i = goal_i; i >= 0; i = parent_[i]) {
    pts.push_back(map.center_of(i % w, i / w));
    cost_to_come.push_back(g_[i]);
  }
  std::reverse(pts.begin(), pts.end());
  std::reverse(cost_to_come.begin(), cost_to_come.end());
  pts.front() = from.head<2>();
  if (pts.size() == 1) {
    pts.push_back(goal.head<2>());
  } else {
    pts.back() = goal.head<2>();
  }
  if (params_.smooth && pts.size() > 2) pts = shortcut(map, trav, pts, cost_to_come);
  pts = resample(pts, map.resolution());
  if (params_.smooth) smooth(map, trav, params_, pts);

  result.path.reserve(escape.size() + pts.size());
  result.path = escape;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    double heading = goal.z();
    if (i + 1 < pts.size()) {
      const Eigen::Vector2d d = pts[i + 1] - pts[i];
      if (d.squaredNorm() > 1e-12) heading = std::atan2(d.y(), d.x());
    }
    if (i == 0 && !escape.empty()) heading = start.z();  // where the escape ends, as it began
    result.path.emplace_back(pts[i].x(), pts[i].y(), heading);
    if (i > 0) result.length += (pts[i] - pts[i - 1]).norm();
  }
  result.status = PlanStatus::kOk;
  result.total_time = seconds_since(t0);
  return result;
}

}  // namespace concert::nav
