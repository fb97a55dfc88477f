#include "planning_fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace concert::nav::testing {

namespace {

// Cells whose centres lie in [lo, hi] (map frame [m]) get `value`.
void fill_rect(bim::OccupancyGrid& grid, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
               std::int8_t value) {
  const Eigen::Vector2i a = grid.cell_of(lo);
  const Eigen::Vector2i b = grid.cell_of(hi);
  for (int r = std::max(a.y(), 0); r <= std::min(b.y(), grid.height - 1); ++r) {
    for (int c = std::max(a.x(), 0); c <= std::min(b.x(), grid.width - 1); ++c) {
      const Eigen::Vector2d p = grid.center_of(c, r);
      if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) grid.at(c, r) = value;
    }
  }
}

}  // namespace

Building make_building(int rooms_x, int rooms_y, double room, double wall, double door,
                       double resolution, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const double w = rooms_x * room + wall;
  const double h = rooms_y * room + wall;
  Building b;
  b.map = bim::OccupancyGrid::filled(static_cast<int>(std::ceil(w / resolution)),
                                     static_cast<int>(std::ceil(h / resolution)), resolution,
                                     {0.0, 0.0});
  std::uniform_real_distribution<double> offset(0.3, room - wall - door - 0.3);
  for (int i = 0; i <= rooms_x; ++i) {  // walls across x, at x = i * room
    fill_rect(b.map, {i * room, 0.0}, {i * room + wall, h}, bim::OccupancyGrid::kOccupied);
  }
  for (int j = 0; j <= rooms_y; ++j) {  // walls across y, at y = j * room
    fill_rect(b.map, {0.0, j * room}, {w, j * room + wall}, bim::OccupancyGrid::kOccupied);
  }
  for (int i = 1; i < rooms_x; ++i) {
    for (int j = 0; j < rooms_y; ++j) {
      const double y0 = j * room + wall + offset(rng);
      fill_rect(b.map, {i * room, y0}, {i * room + wall, y0 + door}, bim::OccupancyGrid::kFree);
      b.doors.emplace_back(i * room + 0.5 * wall, y0 + 0.5 * door);
    }
  }
  for (int j = 1; j < rooms_y; ++j) {
    for (int i = 0; i < rooms_x; ++i) {
      const double x0 = i * room + wall + offset(rng);
      fill_rect(b.map, {x0, j * room}, {x0 + door, j * room + wall}, bim::OccupancyGrid::kFree);
      b.doors.emplace_back(x0 + 0.5 * door, j * room + 0.5 * wall);
    }
  }
  return b;
}

Building two_rooms(bool door_open) {
  Building b;
  b.map = bim::OccupancyGrid::filled(200, 80, 0.05, {0.0, 0.0});
  const auto occ = bim::OccupancyGrid::kOccupied;
  fill_rect(b.map, {0.0, 0.0}, {10.0, 0.2}, occ);
  fill_rect(b.map, {0.0, 3.8}, {10.0, 4.0}, occ);
  fill_rect(b.map, {0.0, 0.0}, {0.2, 4.0}, occ);
  fill_rect(b.map, {9.8, 0.0}, {10.0, 4.0}, occ);
  fill_rect(b.map, {4.9, 0.0}, {5.1, 4.0}, occ);
  if (door_open) {
    fill_rect(b.map, {4.9, 1.5}, {5.1, 2.5}, bim::OccupancyGrid::kFree);
    b.doors.emplace_back(5.0, 2.0);
  }
  return b;
}

void add_box(bim::OccupancyGrid& grid, const Eigen::Vector2d& centre,
             const Eigen::Vector2d& half_size) {
  fill_rect(grid, centre - half_size, centre + half_size, bim::OccupancyGrid::kOccupied);
}

std::vector<Beam> cast_scan(const bim::OccupancyGrid& truth, const Eigen::Vector2d& origin,
                            int beams, double max_range) {
  std::vector<Beam> out;
  out.reserve(static_cast<std::size_t>(beams));
  const double res = truth.resolution;
  for (int k = 0; k < beams; ++k) {
    const double a = 2.0 * M_PI * k / beams;
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    // Amanatides-Woo traversal of the cells along the ray.
    Eigen::Vector2i cell = truth.cell_of(origin);
    const int step_c = d.x() >= 0 ? 1 : -1;
    const int step_r = d.y() >= 0 ? 1 : -1;
    const Eigen::Vector2d rel = (origin - truth.origin) / res;
    const double inf = std::numeric_limits<double>::infinity();
    const double dtc = d.x() != 0.0 ? res / std::abs(d.x()) : inf;
    const double dtr = d.y() != 0.0 ? res / std::abs(d.y()) : inf;
    double tc =
        d.x() != 0.0 ? ((step_c > 0 ? cell.x() + 1 - rel.x() : rel.x() - cell.x()) * dtc) : inf;
    double tr =
        d.y() != 0.0 ? ((step_r > 0 ? cell.y() + 1 - rel.y() : rel.y() - cell.y()) * dtr) : inf;
    Beam beam{origin + max_range * d, false};
    while (true) {
      double t;
      if (tc < tr) {
        t = tc;
        tc += dtc;
        cell.x() += step_c;
      } else {
        t = tr;
        tr += dtr;
        cell.y() += step_r;
      }
      if (t > max_range) break;
      if (!truth.inside(cell.x(), cell.y()) ||
          truth.at(cell.x(), cell.y()) == bim::OccupancyGrid::kOccupied) {
        beam = {origin + (t + 1e-6) * d, true};
        break;
      }
    }
    out.push_back(beam);
  }
  return out;
}

RobotShape test_robot() { return RobotShape::rectangle(0.7, 0.5); }

std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> random_pairs(const Costmap& costmap,
                                                                      int count,
                                                                      double min_distance,
                                                                      std::mt19937& rng) {
  std::uniform_real_distribution<double> ux(
      costmap.origin().x(), costmap.origin().x() + costmap.width() * costmap.resolution());
  std::uniform_real_distribution<double> uy(
      costmap.origin().y(), costmap.origin().y() + costmap.height() * costmap.resolution());
  std::uniform_real_distribution<double> ut(-M_PI, M_PI);
  auto sample = [&] {
    while (true) {
      const Eigen::Vector3d p(ux(rng), uy(rng), ut(rng));
      if (costmap.cost_at(p.head<2>()) < costmap.possibly_colliding_cost() &&
          !costmap.in_collision(p))
        return p;
    }
  };
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
  while (static_cast<int>(pairs.size()) < count) {
    const Eigen::Vector3d s = sample();
    const Eigen::Vector3d g = sample();
    if ((s.head<2>() - g.head<2>()).norm() >= min_distance) pairs.emplace_back(s, g);
  }
  return pairs;
}

std::vector<Eigen::Vector2d> add_obstacles_on_path(bim::OccupancyGrid& truth, const Path& path,
                                                   const std::vector<Eigen::Vector2d>& doors,
                                                   int count, double door_clearance,
                                                   std::mt19937& rng) {
  std::vector<double> along{0.0};
  for (std::size_t i = 1; i < path.size(); ++i) {
    along.push_back(along.back() + (path[i].head<2>() - path[i - 1].head<2>()).norm());
  }
  std::vector<Eigen::Vector2d> centres;
  const double length = along.back();
  if (length < 3.5) return centres;
  std::uniform_real_distribution<double> us(1.5, length - 1.5);
  std::uniform_real_distribution<double> lateral(-0.15, 0.15);
  std::uniform_real_distribution<double> half(0.15, 0.3);
  for (int k = 0, tries = 0; k < count && tries < 100; ++tries) {
    const double s = us(rng);
    const auto i =
        static_cast<std::size_t>(std::lower_bound(along.begin(), along.end(), s) - along.begin());
    const Eigen::Vector3d& q = path[std::min(i, path.size() - 1)];
    const Eigen::Vector2d c =
        q.head<2>() + lateral(rng) * Eigen::Vector2d(-std::sin(q.z()), std::cos(q.z()));
    const bool near_door = std::any_of(doors.begin(), doors.end(), [&](const Eigen::Vector2d& d) {
      return (d - c).norm() < door_clearance;
    });
    const bool near_ends =
        (c - path.front().head<2>()).norm() < 1.2 || (c - path.back().head<2>()).norm() < 1.2;
    if (near_door || near_ends) continue;
    add_box(truth, c, {half(rng), half(rng)});
    centres.push_back(c);
    ++k;
  }
  return centres;
}

RunResult run_mission(const bim::OccupancyGrid& map, const bim::OccupancyGrid& truth,
                      const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                      const SimConfig& config) {
  RunResult result;
  Costmap costmap(map, config.shape, config.costmap);
  CostmapParams exact;
  exact.inflation_radius = 0.0;
  const Costmap truth_map(truth, config.shape, exact);
  GlobalPlanner planner(config.planner);
  LocalController controller(config.controller);
  std::mt19937 rng(config.seed);
  std::normal_distribution<double> noise(0.0, config.velocity_noise);
  const ControllerParams::Limits& lim = config.controller.limits;

  Eigen::Vector3d pose = start;
  BaseTwist velocity;
  auto finish = [&](std::string failure) {
    result.failure = std::move(failure);
    result.position_error = (pose.head<2>() - goal.head<2>()).norm();
    result.heading_error =
        std::abs(std::atan2(std::sin(goal.z() - pose.z()), std::cos(goal.z() - pose.z())));
    return result;
  };
  auto replan = [&]() -> bool {
    const PlanResult plan = planner.plan(costmap, pose, goal);
    if (!plan.ok()) {
      result.failure = std::string("plan: ") + plan.message;
      return false;
    }
    controller.set_path(plan.path);
    return true;
  };
  if (!replan()) return finish(result.failure);
  result.trajectory.push_back(pose);
  for (int step = 0; step * config.dt < config.max_time; ++step) {
    const double t = step * config.dt;
    result.time = t;
    if (step % config.scan_every == 0) {
      costmap.update_obstacles(
          pose.head<2>(), cast_scan(truth, pose.head<2>(), config.scan_beams, config.scan_range));
    }
    const ControlOutput out = controller.compute(costmap, pose, t);
    if (out.status == ControlStatus::kReached) {
      result.reached = true;
      return finish("");
    }
    BaseTwist cmd = out.cmd;
    if (out.status == ControlStatus::kBlocked || out.status == ControlStatus::kFailed) {
      result.was_blocked = result.was_blocked || out.status == ControlStatus::kBlocked;
      if (++result.replans > config.max_replans)
        return finish("too many replans; last: " + out.reason);
      if (!replan()) return finish(result.failure + " (after: " + out.reason + ")");
      cmd = {};
    }
    // The plant: acceleration-limited tracking of the command, with seeded velocity noise.
    auto track = [&](double v, double target, double accel) {
      return std::clamp(target, v - accel * config.dt, v + accel * config.dt);
    };
    velocity.vx = track(velocity.vx, cmd.vx, lim.max_ax);
    velocity.vy = track(velocity.vy, cmd.vy, lim.max_ay);
    velocity.wz = track(velocity.wz, cmd.wz, lim.max_aw);
    BaseTwist executed = velocity;
    executed.vx *= 1.0 + noise(rng);
    executed.vy *= 1.0 + noise(rng);
    executed.wz *= 1.0 + noise(rng);
    pose = integrate_twist(pose, executed, config.dt);
    result.trajectory.push_back(pose);
    if (truth_map.in_collision(pose)) {
      result.collided = true;
      return finish("collision at step " + std::to_string(step));
    }
  }
  return finish("time out after " + std::to_string(config.max_time) + " s");
}

}  // namespace concert::nav::testing
