#include "nav/costmap.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "grid_line.hpp"

namespace concert::nav {

namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

RobotShape RobotShape::from_footprint(FootprintPolygon footprint) {
  const std::size_t n = footprint.size();
  if (n < 3) {
    throw std::invalid_argument("robot footprint: " + std::to_string(n) +
                                " vertices; a polygon needs at least 3");
  }
  double sign = 0.0;
  double inscribed = std::numeric_limits<double>::infinity();
  double circumscribed = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = footprint[i];
    const Eigen::Vector2d& b = footprint[(i + 1) % n];
    const Eigen::Vector2d& c = footprint[(i + 2) % n];
    if (!a.allFinite())
      throw std::invalid_argument("robot footprint: vertex " + std::to_string(i) +
                                  " is not finite");
    const Eigen::Vector2d edge = b - a;
    const double len = edge.norm();
    if (len <= 0.0) {
      throw std::invalid_argument("robot footprint: vertices " + std::to_string(i) + " and " +
                                  std::to_string((i + 1) % n) + " coincide");
    }
    const double turn = cross(edge, c - b);
    const double side = cross(edge, -a);  // origin relative to the edge
    if (turn != 0.0) {
      if (sign == 0.0) sign = turn > 0 ? 1.0 : -1.0;
      if (turn * sign < 0.0) {
        throw std::invalid_argument("robot footprint: not convex at vertex " +
                                    std::to_string((i + 1) % n));
      }
    }
    inscribed = std::min(inscribed, std::abs(side) / len);
    circumscribed = std::max(circumscribed, a.norm());
  }
  if (sign == 0.0) throw std::invalid_argument("robot footprint: all vertices on one line");
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d edge = footprint[(i + 1) % n] - footprint[i];
    if (cross(edge, -footprint[i]) * sign <= 0.0) {
      throw std::invalid_argument("robot footprint: the base origin is not strictly inside (edge " +
                                  std::to_string(i) + ")");
    }
  }
  RobotShape shape;
  shape.footprint = std::move(footprint);
  shape.inscribed_radius = inscribed;
  shape.circumscribed_radius = circumscribed;
  return shape;
}

RobotShape RobotShape::rectangle(double length, double width) {
  if (!(length > 0.0) || !(width > 0.0)) {
    throw std::invalid_argument("robot rectangle " + fmt(length) + " x " + fmt(width) +
                                " m: both sides must be > 0");
  }
  const double hx = 0.5 * length;
  const double hy = 0.5 * width;
  return from_footprint({{hx, hy}, {-hx, hy}, {-hx, -hy}, {hx, -hy}});
}

Costmap::Costmap(const bim::OccupancyGrid& map, const RobotShape& shape,
                 const CostmapParams& params)
    : width_(map.width),
      height_(map.height),
      resolution_(map.resolution),
      origin_(map.origin),
      shape_(shape),
      params_(params) {
  if (width_ <= 0 || height_ <= 0 ||
      map.cells.size() != static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_)) {
    throw std::invalid_argument("costmap: the occupancy grid's " +
                                std::to_string(map.cells.size()) + " cells do not match its size " +
                                std::to_string(width_) + " x " + std::to_string(height_));
  }
  if (!(resolution_ > 0.0))
    throw std::invalid_argument("costmap: map resolution " + fmt(resolution_) + " m: must be > 0");
  if (shape_.footprint.size() < 3)
    throw std::invalid_argument("costmap: the robot footprint has fewer than 3 vertices");
  if (!(shape_.inscribed_radius > 0.0) || shape_.circumscribed_radius < shape_.inscribed_radius) {
    throw std::invalid_argument("costmap: inscribed radius " + fmt(shape_.inscribed_radius) +
                                " m and circumscribed radius " + fmt(shape_.circumscribed_radius) +
                                " m: need 0 < inscribed <= circumscribed");
  }
  if (!(params_.inflation_radius >= 0.0))
    throw std::invalid_argument("costmap: inflation_radius " + fmt(params_.inflation_radius) +
                                " m: must be >= 0");
  if (!(params_.cost_scaling_factor > 0.0))
    throw std::invalid_argument("costmap: cost_scaling_factor " + fmt(params_.cost_scaling_factor) +
                                " 1/m: must be > 0");
  if (!(params_.obstacle_max_range > 0.0) || !(params_.raytrace_max_range > 0.0)) {
    throw std::invalid_argument("costmap: obstacle_max_range " + fmt(params_.obstacle_max_range) +
                                " m and raytrace_max_range " + fmt(params_.raytrace_max_range) +
                                " m: both must be > 0");
  }

  inflation_cells_ = static_cast<int>(std::ceil(params_.inflation_radius / resolution_));
  for (int dy = -inflation_cells_; dy <= inflation_cells_; ++dy) {
    for (int dx = -inflation_cells_; dx <= inflation_cells_; ++dx) {
      const double d = resolution_ * std::hypot(dx, dy);
      if (d > params_.inflation_radius) continue;
      const std::uint8_t c = inflation_cost(d);
      if (c > 0) kernel_.push_back({dx, dy, c});
    }
  }
  possibly_colliding_ = inflation_cost(shape_.circumscribed_radius);
  const bool inflated_far_enough =
      params_.inflation_radius >= shape_.circumscribed_radius + std::sqrt(2.0) * resolution_;
  fast_free_cost_ = inflated_far_enough && params_.unknown_is_lethal
                        ? inflation_cost(shape_.circumscribed_radius + std::sqrt(2.0) * resolution_)
                        : 0;

  const std::size_t n = map.cells.size();
  static_.resize(n);
  unknown_.resize(n);
  obstacle_.assign(n, 0);
  master_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int8_t v = map.cells[i];
    unknown_[i] = v == bim::OccupancyGrid::kUnknown ? 1 : 0;
    if (v == bim::OccupancyGrid::kOccupied) {
      static_[i] = kLethal;
    } else if (v == bim::OccupancyGrid::kUnknown) {
      static_[i] = params_.unknown_is_lethal ? kLethal : kNoInformation;
    } else {
      static_[i] = kFree;
    }
  }
  reinflate(0, 0, width_ - 1, height_ - 1);
}

Eigen::Vector2i Costmap::cell_of(const Eigen::Vector2d& p) const {
  return {static_cast<int>(std::floor((p.x() - origin_.x()) / resolution_)),
          static_cast<int>(std::floor((p.y() - origin_.y()) / resolution_))};
}

Eigen::Vector2d Costmap::center_of(int col, int row) const {
  return origin_ + resolution_ * Eigen::Vector2d(col + 0.5, row + 0.5);
}

std::uint8_t Costmap::cost_at(const Eigen::Vector2d& p) const {
  const Eigen::Vector2i c = cell_of(p);
  return inside(c.x(), c.y()) ? cost(c.x(), c.y()) : kLethal;
}

std::uint8_t Costmap::inflation_cost(double distance) const {
  if (distance <= 0.0) return kLethal;
  if (distance <= shape_.inscribed_radius) return kInscribed;
  if (distance > params_.inflation_radius) return kFree;
  const double factor =
      std::exp(-params_.cost_scaling_factor * (distance - shape_.inscribed_radius));
  return static_cast<std::uint8_t>((kInscribed - 1) * factor);
}

double Costmap::distance_from_cost(std::uint8_t cost) const {
  if (cost >= kInscribed) return 0.0;
  if (cost == kFree) return params_.inflation_radius;
  return shape_.inscribed_radius -
         std::log(static_cast<double>(cost) / (kInscribed - 1)) / params_.cost_scaling_factor;
}

bool Costmap::lethal_base(int col, int row) const {
  const std::size_t i = index(col, row);
  return static_[i] == kLethal || obstacle_[i] != 0;
}

std::uint8_t Costmap::base_cost(std::size_t i) const {
  return obstacle_[i] != 0 ? kLethal : static_[i];
}

void Costmap::reinflate(int c0, int r0, int c1, int r1) {
  c0 = std::max(c0, 0);
  r0 = std::max(r0, 0);
  c1 = std::min(c1, width_ - 1);
  r1 = std::min(r1, height_ - 1);
  if (c0 > c1 || r0 > r1) return;
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) master_[index(c, r)] = base_cost(index(c, r));
  }
  // Sources: lethal cells within the inflation radius of the window that border a non-lethal
  // cell (an interior lethal cell always has a nearer lethal neighbour).
  const int sc0 = std::max(c0 - inflation_cells_, 0);
  const int sr0 = std::max(r0 - inflation_cells_, 0);
  const int sc1 = std::min(c1 + inflation_cells_, width_ - 1);
  const int sr1 = std::min(r1 + inflation_cells_, height_ - 1);
  for (int r = sr0; r <= sr1; ++r) {
    for (int c = sc0; c <= sc1; ++c) {
      if (!lethal_base(c, r)) continue;
      const bool border =
          (c > 0 && !lethal_base(c - 1, r)) || (c + 1 < width_ && !lethal_base(c + 1, r)) ||
          (r > 0 && !lethal_base(c, r - 1)) || (r + 1 < height_ && !lethal_base(c, r + 1));
      if (!border) continue;
      for (const KernelCell& k : kernel_) {
        const int cc = c + k.dx;
        const int rr = r + k.dy;
        if (cc < c0 || cc > c1 || rr < r0 || rr > r1) continue;
        std::uint8_t& m = master_[index(cc, rr)];
        if (m == kNoInformation) {
          if (k.cost >= kInscribed) m = k.cost;  // nav2: unknown stays unless (nearly) lethal
        } else if (k.cost > m) {
          m = k.cost;
        }
      }
    }
  }
}

namespace {

// The footprint's cells at a pose: per row of the bounding box, the columns whose centres lie
// inside the convex polygon, plus the cells its edges cross. Returns false (and visits nothing)
// when any of them lies outside the map.
template <typename Visit>
bool visit_footprint(const Costmap& map, const FootprintPolygon& footprint, const Eigen::Vector3d& pose,
                     Visit&& visit) {
  const Eigen::Rotation2Dd rot(pose.z());
  const Eigen::Vector2d t = pose.head<2>();
  Eigen::Vector2d lo(std::numeric_limits<double>::infinity(),
                     std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  thread_local std::vector<Eigen::Vector2d> pts;
  pts.clear();
  for (const Eigen::Vector2d& v : footprint) {
    pts.push_back(t + rot * v);
    lo = lo.cwiseMin(pts.back());
    hi = hi.cwiseMax(pts.back());
  }
  const Eigen::Vector2i clo = map.cell_of(lo);
  const Eigen::Vector2i chi = map.cell_of(hi);
  if (!map.inside(clo.x(), clo.y()) || !map.inside(chi.x(), chi.y())) return false;
  const std::size_t n = pts.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2i a = map.cell_of(pts[i]);
    const Eigen::Vector2i b = map.cell_of(pts[(i + 1) % n]);
    if (!detail::trace_line(a.x(), a.y(), b.x(), b.y(), visit)) return true;
  }
  const double res = map.resolution();
  for (int r = clo.y(); r <= chi.y(); ++r) {
    const double y = map.origin().y() + (r + 0.5) * res;
    double xmin = std::numeric_limits<double>::infinity();
    double xmax = -xmin;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d& a = pts[i];
      const Eigen::Vector2d& b = pts[(i + 1) % n];
      if ((a.y() - y) * (b.y() - y) > 0.0 || a.y() == b.y()) continue;
      const double x = a.x() + (y - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
      xmin = std::min(xmin, x);
      xmax = std::max(xmax, x);
    }
    if (xmin > xmax) continue;
    const int cmin = static_cast<int>(std::ceil((xmin - map.origin().x()) / res - 0.5));
    const int cmax = static_cast<int>(std::floor((xmax - map.origin().x()) / res - 0.5));
    for (int c = std::max(cmin, clo.x()); c <= std::min(cmax, chi.x()); ++c) {
      if (!visit(c, r)) return true;
    }
  }
  return true;
}

}  // namespace

std::uint8_t Costmap::footprint_cost(const Eigen::Vector3d& pose) const {
  std::uint8_t worst = kFree;
  const bool inside_map = visit_footprint(*this, shape_.footprint, pose, [&](int c, int r) {
    worst = std::max(worst, cost(c, r));
    return true;
  });
  return inside_map ? worst : kLethal;
}

bool Costmap::free_at_any_heading(const Eigen::Vector2d& p) const {
  const double reach = shape_.circumscribed_radius + std::sqrt(0.5) * resolution_;
  const Eigen::Vector2i lo = cell_of(p - Eigen::Vector2d::Constant(reach));
  const Eigen::Vector2i hi = cell_of(p + Eigen::Vector2d::Constant(reach));
  if (!inside(lo.x(), lo.y()) || !inside(hi.x(), hi.y())) return false;
  for (int r = lo.y(); r <= hi.y(); ++r) {
    for (int c = lo.x(); c <= hi.x(); ++c) {
      if (cost(c, r) == kLethal && (center_of(c, r) - p).norm() <= reach) return false;
    }
  }
  return true;
}

bool Costmap::in_collision(const Eigen::Vector3d& pose) const {
  const Eigen::Vector2i centre = cell_of(pose.head<2>());
  if (!inside(centre.x(), centre.y())) return true;
  if (cost(centre.x(), centre.y()) < fast_free_cost_) {
    const double reach = shape_.circumscribed_radius;
    const Eigen::Vector2i lo = cell_of(pose.head<2>() - Eigen::Vector2d::Constant(reach));
    const Eigen::Vector2i hi = cell_of(pose.head<2>() + Eigen::Vector2d::Constant(reach));
    if (inside(lo.x(), lo.y()) && inside(hi.x(), hi.y())) return false;
  }
  bool hit = false;
  const bool inside_map = visit_footprint(*this, shape_.footprint, pose, [&](int c, int r) {
    hit = cost(c, r) == kLethal;
    return !hit;
  });
  return !inside_map || hit;
}

double Costmap::lethal_depth(const Eigen::Vector3d& pose) const {
  const FootprintPolygon& fp = shape_.footprint;
  const Eigen::Rotation2Dd to_base(-pose.z());
  double area = 0.0;  // twice the signed area: > 0 for a counter-clockwise polygon
  for (std::size_t i = 0; i < fp.size(); ++i) {
    const Eigen::Vector2d& a = fp[i];
    const Eigen::Vector2d& b = fp[(i + 1) % fp.size()];
    area += a.x() * b.y() - a.y() * b.x();
  }
  const double turn = area >= 0.0 ? 1.0 : -1.0;
  double depth = 0.0;
  const bool inside_map = visit_footprint(*this, fp, pose, [&](int c, int r) {
    if (cost(c, r) != kLethal) return true;
    const Eigen::Vector2d p = to_base * (center_of(c, r) - pose.head<2>());
    double inside = std::numeric_limits<double>::infinity();  // to the nearest edge; < 0: outside
    for (std::size_t i = 0; i < fp.size(); ++i) {
      const Eigen::Vector2d& e0 = fp[i];
      const Eigen::Vector2d e = fp[(i + 1) % fp.size()] - e0;
      const Eigen::Vector2d d = p - e0;
      inside = std::min(inside, turn * (e.x() * d.y() - e.y() * d.x()) / e.norm());
    }
    depth = std::max(depth, inside);
    return true;
  });
  return inside_map ? depth : std::numeric_limits<double>::infinity();
}

void Costmap::touch(CostmapUpdate& up, int col, int row) const {
  if (up.window[0] > up.window[2]) {
    up.window = {col, row, col, row};
    return;
  }
  up.window[0] = std::min(up.window[0], col);
  up.window[1] = std::min(up.window[1], row);
  up.window[2] = std::max(up.window[2], col);
  up.window[3] = std::max(up.window[3], row);
}

void Costmap::reinflate_changed(CostmapUpdate& up) {
  if (up.window[0] > up.window[2]) return;
  // A changed cell alters costs up to the inflation radius around it.
  up.window[0] = std::max(up.window[0] - inflation_cells_ - 1, 0);
  up.window[1] = std::max(up.window[1] - inflation_cells_ - 1, 0);
  up.window[2] = std::min(up.window[2] + inflation_cells_ + 1, width_ - 1);
  up.window[3] = std::min(up.window[3] + inflation_cells_ + 1, height_ - 1);
  reinflate(up.window[0], up.window[1], up.window[2], up.window[3]);
}

CostmapUpdate Costmap::update_obstacles(const Eigen::Vector2d& sensor_origin,
                                        std::span<const Beam> beams) {
  CostmapUpdate up;
  const Eigen::Vector2i o = cell_of(sensor_origin);
  // Clear along every beam first, then mark, so that one beam never clears another's hit.
  for (const Beam& beam : beams) {
    Eigen::Vector2d dir = beam.end - sensor_origin;
    const double len = dir.norm();
    if (!std::isfinite(len) || len <= 0.0) continue;
    const double reach = std::min(len, params_.raytrace_max_range);
    const Eigen::Vector2i e = cell_of(sensor_origin + dir * (reach / len));
    const bool ends_in_hit = beam.hit && reach == len;
    detail::trace_line(o.x(), o.y(), e.x(), e.y(), [&](int c, int r) {
      if (ends_in_hit && c == e.x() && r == e.y()) return false;
      if (inside(c, r)) {
        std::uint8_t& m = obstacle_[index(c, r)];
        if (m != 0) {
          m = 0;
          ++up.cleared;
          touch(up, c, r);
        }
      }
      return true;
    });
  }
  for (const Beam& beam : beams) {
    if (!beam.hit) continue;
    const double len = (beam.end - sensor_origin).norm();
    if (!std::isfinite(len) || len > params_.obstacle_max_range) continue;
    const Eigen::Vector2i e = cell_of(beam.end);
    if (!inside(e.x(), e.y())) continue;
    std::uint8_t& m = obstacle_[index(e.x(), e.y())];
    if (m == 0) {
      m = 1;
      ++up.marked;
      touch(up, e.x(), e.y());
    }
  }
  reinflate_changed(up);
  return up;
}

CostmapUpdate Costmap::update_obstacles(const Eigen::Vector2d& sensor_origin,
                                        std::span<const Eigen::Vector2d> hits) {
  std::vector<Beam> beams;
  beams.reserve(hits.size());
  for (const Eigen::Vector2d& p : hits) beams.push_back({p, true});
  return update_obstacles(sensor_origin, beams);
}

CostmapUpdate Costmap::clear_obstacles() {
  CostmapUpdate up;
  for (int r = 0; r < height_; ++r) {
    for (int c = 0; c < width_; ++c) {
      std::uint8_t& m = obstacle_[index(c, r)];
      if (m != 0) {
        m = 0;
        ++up.cleared;
        touch(up, c, r);
      }
    }
  }
  reinflate_changed(up);
  return up;
}

}  // namespace concert::nav
