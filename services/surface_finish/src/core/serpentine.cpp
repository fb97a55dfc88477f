#include "surface_finish/serpentine.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace concert::surface_finish {

namespace {

std::string at(const PathSample& s) {
  char b[128];
  if (s.stroke >= 0) {
    std::snprintf(b, sizeof b, "stroke %d at (%.2f, %.2f) m", s.stroke + 1, s.wall.x(), s.wall.y());
  } else {
    std::snprintf(b, sizeof b, "(%.2f, %.2f) m, %.2f m off the wall", s.wall.x(), s.wall.y(), s.wall.z());
  }
  return b;
}

// Samples of a straight segment a -> b (wall coordinates) at rest at both ends, trapezoidal
// speed; appended from time t0 (the first sample, at a, is skipped: the previous segment ends there).
void segment(std::vector<PathSample>& out, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double speed,
             double accel, double period, int stroke, bool on) {
  const double length = (b - a).norm();
  const double t0 = out.empty() ? 0.0 : out.back().t;
  if (length < 1e-9) return;
  const double v = std::min(speed, std::sqrt(length * accel));
  const double ta = v / accel;
  const double tc = std::max(0.0, (length - v * ta) / v);
  const double total = 2.0 * ta + tc;
  const int n = std::max(1, static_cast<int>(std::ceil(total / period)));
  for (int i = 1; i <= n; ++i) {
    const double t = total * i / n;
    double s = 0.0;
    if (t < ta) {
      s = 0.5 * accel * t * t;
    } else if (t < ta + tc) {
      s = 0.5 * accel * ta * ta + v * (t - ta);
    } else {
      const double td = total - t;
      s = length - 0.5 * accel * td * td;
    }
    PathSample p;
    p.t = t0 + t;
    p.wall = a + (b - a) * (s / length);
    p.stroke = stroke;
    p.tool_on = on;
    out.push_back(p);
  }
}

}  // namespace

bool valve_open(const Stroke& stroke, const Eigen::Vector3d& tcp_wall) {
  const double progress = (tcp_wall.y() - stroke.y_start) * (stroke.up() ? 1.0 : -1.0);
  return progress >= 0.0 && progress <= std::abs(stroke.y_end - stroke.y_start);
}

std::size_t track_sample(const SerpentinePlan& plan, const std::vector<int>& arm, std::size_t from,
                         const Eigen::VectorXd& q, std::size_t window) {
  const auto& samples = plan.samples;
  if (samples.empty()) return 0;
  from = std::min(from, samples.size() - 1);
  const auto distance = [&](const Eigen::VectorXd& a) {
    double d = 0.0;
    for (const int j : arm) d += (a[j] - q[j]) * (a[j] - q[j]);
    return d;
  };
  std::size_t best = from;
  double best_d = distance(samples[from].q);
  for (std::size_t i = from + 1; i < samples.size() && i <= from + window; ++i) {
    const double d = distance(samples[i].q);
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

int stroke_count(double width, double coat_width, double overlap) {
  if (!(width > 0.0) || !(coat_width > 0.0)) {
    throw FinishError("stroke count: width " + std::to_string(width) + " m and coat width " +
                      std::to_string(coat_width) + " m must be positive");
  }
  if (!(overlap >= 0.0 && overlap <= 0.9)) {
    throw FinishError("stroke count: overlap " + std::to_string(overlap) + " outside [0, 0.9]");
  }
  if (width <= coat_width + 1e-9) return 1;
  return static_cast<int>(std::ceil((width - coat_width) / (coat_width * (1.0 - overlap)) - 1e-9)) + 1;
}

std::vector<Stroke> serpentine_strokes(const Rect& rect, const ToolSpec& tool, double visible, double* spacing,
                                       double* end_extension) {
  if (!(rect.width() > 0.0) || !(rect.height() > 0.0)) throw FinishError("rectangle " + rect.str() + " has no positive size");
  const int n = stroke_count(rect.width(), tool.coat_width, tool.overlap);
  const double c = tool.coat_width;
  const double r = 0.5 * c;
  const double s = n > 1 ? (rect.width() - c) / (n - 1) : c;
  // The coat reaches the rectangle's lower and upper edges half a spacing each side of the
  // stroke when the stroke's centre stops `a` short of the edge: sqrt(r^2 - (s/2)^2) minus the
  // length of path the film needs to become visible (2 r visible: the film is proportional to
  // the length of path over the point, 2 r for a full pass over the centre line).
  const double half = std::min(0.5 * s, r);
  const double a = std::sqrt(std::max(0.0, r * r - half * half)) - 2.0 * r * (tool.task == Task::kSpray ? visible : 0.0);
  const double y_low = rect.y0 + a;
  const double y_high = rect.y1 - a;
  if (y_high <= y_low) throw FinishError("rectangle " + rect.str() + " is lower than one coat");
  if (spacing != nullptr) *spacing = s;
  if (end_extension != nullptr) *end_extension = r - a;
  std::vector<Stroke> strokes;
  for (int i = 0; i < n; ++i) {
    const double x = n > 1 ? rect.x0 + r + i * s : 0.5 * (rect.x0 + rect.x1);
    const bool up = i % 2 == 0;
    strokes.push_back(Stroke{x, up ? y_low : y_high, up ? y_high : y_low});
  }
  return strokes;
}

SerpentinePlan plan_serpentine(Reach& reach, const WallFrame& wall, const Rect& rect, const ToolSpec& tool,
                               double roll, const PathParams& params, const Eigen::VectorXd& q_start,
                               const Eigen::VectorXd* path_seed) {
  if (!(params.speed > 0.0) || !(params.acceleration > 0.0) || !(params.sample_period > 0.0) ||
      !(params.approach_speed > 0.0)) {
    throw FinishError("path parameters: speed, acceleration, sample period and approach speed must be positive");
  }
  if (!(params.approach >= 0.0) || !(params.move_standoff >= 0.0)) {
    throw FinishError("path parameters: the approach and the move's standoff must be >= 0 m");
  }
  const kinematics::Model& k = reach.model().kinematics();
  if (q_start.size() != k.dof()) {
    throw FinishError("start posture has " + std::to_string(q_start.size()) + " joints, model version " +
                      std::to_string(reach.model().version()) + " has " + std::to_string(k.dof()));
  }
  SerpentinePlan plan;
  plan.rect = rect;
  plan.tool = tool;
  plan.params = params;
  plan.roll = roll;
  plan.strokes = serpentine_strokes(rect, tool, params.visible, &plan.spacing, &plan.end_extension);

  // Cartesian path in wall coordinates.
  std::vector<PathSample> path;
  const double off = tool.standoff;
  const Stroke& first = plan.strokes.front();
  const Stroke& last = plan.strokes.back();
  PathSample p0;
  const double stage = std::max(0.0, params.move_standoff - (off + params.approach));
  p0.wall = Eigen::Vector3d(first.x, first.y_start, off + params.approach + stage);
  path.push_back(p0);
  if (stage > 0.0) {
    segment(path, p0.wall, Eigen::Vector3d(first.x, first.y_start, off + params.approach), params.approach_speed,
            params.acceleration, params.sample_period, -1, false);
  }
  const std::size_t i_approach = path.size() - 1;  // the approach pose
  const Eigen::Vector3d approach_pose = path.back().wall;  // a copy: segment() appends to path
  segment(path, approach_pose, Eigen::Vector3d(first.x, first.y_start, off), params.approach_speed,
          params.acceleration, params.sample_period, -1, false);
  for (std::size_t i = 0; i < plan.strokes.size(); ++i) {
    const Stroke& s = plan.strokes[i];
    if (i > 0) {
      const Stroke& prev = plan.strokes[i - 1];
      segment(path, Eigen::Vector3d(prev.x, prev.y_end, off), Eigen::Vector3d(s.x, s.y_start, off), params.speed,
              params.acceleration, params.sample_period, -1, false);
    }
    segment(path, Eigen::Vector3d(s.x, s.y_start, off), Eigen::Vector3d(s.x, s.y_end, off), params.speed,
            params.acceleration, params.sample_period, static_cast<int>(i), true);
    // Held at the end while the TCP settles.
    const int hold = static_cast<int>(std::ceil(params.settle / params.sample_period));
    for (int h = 0; h < hold; ++h) {
      PathSample p = path.back();
      p.t += params.sample_period;
      path.push_back(p);
    }
  }
  segment(path, Eigen::Vector3d(last.x, last.y_end, off), Eigen::Vector3d(last.x, last.y_end, off + params.approach),
          params.approach_speed, params.acceleration, params.sample_period, -1, false);

  // Joints along it: the approach pose from the seed, the line out to where the joint move ends
  // back from it (the path's branch is the approach pose's), the rest each from its predecessor.
  auto solve = [&](std::size_t i, const Eigen::VectorXd* prev) {
    PathSample& s = path[i];
    s.tcp = Reach::target(wall, s.wall.x(), s.wall.y(), s.wall.z(), roll);
    const Eigen::VectorXd& seed =
        prev != nullptr ? *prev : (path_seed != nullptr && path_seed->size() == q_start.size() ? *path_seed : q_start);
    const ReachPose r = reach.solve(s.tcp, wall, seed, prev, prev == nullptr);
    if (!r.ok) throw FinishError("path refused: " + at(s) + ": " + r.reason);
    s.q = r.q;
  };
  solve(i_approach, nullptr);
  for (std::size_t i = i_approach; i-- > 0;) solve(i, &path[i + 1].q);
  for (std::size_t i = i_approach + 1; i < path.size(); ++i) solve(i, &path[i - 1].q);

  // The move from the start posture to the approach pose, in joint space.
  const Eigen::VectorXd& q0 = path.front().q;
  double move = 0.0;
  for (int j : reach.arm_joints()) {
    const double vmax = k.joint_limits()[static_cast<std::size_t>(j)].velocity;
    const double vel = vmax > 0.0 ? 0.3 * vmax : 0.3;
    move = std::max(move, 1.5 * std::abs(q0[j] - q_start[j]) / vel);
  }
  std::vector<PathSample> out;
  const double start_off = wall.coordinates(reach.tcp_pose(q_start).translation()).z();
  const double clearance = std::min(params.move_clearance, start_off - params.start_tolerance);
  // The same rule for the arm's shapes: a tilted tool's rim comes nearer the wall than its TCP.
  const double shape_clearance =
      std::min(params.move_shape_clearance, reach.wall_clearance(q_start, wall) - params.start_tolerance);
  if (move > 1e-6) {
    move = std::max(move, 1.0);
    const int n = std::max(2, static_cast<int>(std::ceil(move / params.sample_period)));
    for (int i = 0; i < n; ++i) {
      const double u = static_cast<double>(i) / n;
      const double sm = u * u * (3.0 - 2.0 * u);  // smoothstep: at rest at both ends
      PathSample m;
      m.t = move * u;
      m.q = q_start + sm * (q0 - q_start);
      m.tcp = reach.tcp_pose(m.q);
      m.wall = wall.coordinates(m.tcp.translation());
      if (auto hit = reach.self_collision(m.q)) throw FinishError("path refused: move to the approach pose: self collision " + *hit);
      if (m.wall.z() < clearance) {
        char b[160];
        std::snprintf(b, sizeof b, "path refused: the move to the approach pose brings the tool %.0f mm from the wall", m.wall.z() * 1000.0);
        throw FinishError(b);
      }
      std::string link;
      if (const double c = reach.wall_clearance(m.q, wall, &link); c < shape_clearance) {
        char b[200];
        std::snprintf(b, sizeof b, "path refused: the move to the approach pose brings %s %.0f mm from the wall",
                      link.c_str(), c * 1000.0);
        throw FinishError(b);
      }
      out.push_back(m);
    }
  }
  for (PathSample& s : path) {
    s.t += move;
    out.push_back(std::move(s));
  }
  // Velocities and the joints' velocity limits.
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::size_t a = i > 0 ? i - 1 : i;
    const std::size_t b = i + 1 < out.size() ? i + 1 : i;
    out[i].qd = b > a ? Eigen::VectorXd((out[b].q - out[a].q) / (out[b].t - out[a].t)) : Eigen::VectorXd::Zero(k.dof());
    if (i == 0 || i + 1 == out.size()) out[i].qd.setZero();
    for (int j : reach.arm_joints()) {
      const double vmax = k.joint_limits()[static_cast<std::size_t>(j)].velocity;
      if (vmax > 0.0 && std::abs(out[i].qd[j]) > params.velocity_scale * vmax) {
        char b2[200];
        std::snprintf(b2, sizeof b2, "path refused: %s: %s would turn at %.2f rad/s > %.0f %% of its %.2f rad/s limit (lower the speed)",
                      at(out[i]).c_str(), k.joint_names()[static_cast<std::size_t>(j)].c_str(), std::abs(out[i].qd[j]),
                      100.0 * params.velocity_scale, vmax);
        throw FinishError(b2);
      }
    }
  }
  plan.samples = std::move(out);
  return plan;
}

}  // namespace concert::surface_finish
