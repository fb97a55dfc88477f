#include "concert/bim/wall_goal.hpp"

#include <cmath>
#include <deque>
#include <optional>
#include <sstream>

#include "concert/bim/geometry.hpp"

namespace concert::bim {

namespace {

std::string fmt(double v, int digits = 3) {
  std::ostringstream s;
  s.precision(digits);
  s << std::fixed << v;
  return s.str();
}

/// Möller-Trumbore: does the segment p -> q cross the triangle?
bool segment_hits(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d dir = q - p;
  const Eigen::Vector3d e1 = b - a;
  const Eigen::Vector3d e2 = c - a;
  const Eigen::Vector3d pv = dir.cross(e2);
  const double det = e1.dot(pv);
  if (std::abs(det) < 1e-14) return false;
  const Eigen::Vector3d tv = p - a;
  const double u = tv.dot(pv) / det;
  if (u < 0 || u > 1) return false;
  const Eigen::Vector3d qv = tv.cross(e1);
  const double v = dir.dot(qv) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(qv) / det;
  return t >= 0 && t <= 1;
}

bool has_material(const Mesh& mesh, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  for (const auto& t : mesh.triangles) {
    if (segment_hits(p, q, mesh.vertices[static_cast<std::size_t>(t[0])],
                     mesh.vertices[static_cast<std::size_t>(t[1])],
                     mesh.vertices[static_cast<std::size_t>(t[2])])) {
      return true;
    }
  }
  return false;
}

/// Cell offsets whose square comes closer than `radius` to the centre of cell (0, 0).
std::vector<Eigen::Vector2i> disc_offsets(double radius, double res) {
  std::vector<Eigen::Vector2i> out;
  const int n = static_cast<int>(std::ceil(radius / res)) + 1;
  for (int dy = -n; dy <= n; ++dy) {
    for (int dx = -n; dx <= n; ++dx) {
      const double ex = res * std::max(0.0, std::abs(dx) - 0.5);
      const double ey = res * std::max(0.0, std::abs(dy) - 0.5);
      if (ex * ex + ey * ey < radius * radius) out.emplace_back(dx, dy);
    }
  }
  return out;
}

/// The free space of the robot's centre: cells whose robot disc touches only free cells.
std::vector<bool> free_space(const OccupancyGrid& grid, double radius) {
  std::vector<bool> free(grid.cells.size(), true);
  const auto disc = disc_offsets(radius, grid.resolution);
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      if (grid.at(c, r) == OccupancyGrid::kFree) continue;
      for (const auto& o : disc) {
        if (grid.inside(c + o.x(), r + o.y())) free[grid.index(c + o.x(), r + o.y())] = false;
      }
    }
  }
  // Cells whose disc reaches beyond the map are not free either.
  const int n = static_cast<int>(std::ceil(radius / grid.resolution - 0.5));
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      if (c < n || r < n || c >= grid.width - n || r >= grid.height - n)
        free[grid.index(c, r)] = false;
    }
  }
  return free;
}

/// Area of the 4-connected region of `free` holding `start` [m^2].
double region_area(const OccupancyGrid& grid, const std::vector<bool>& free,
                   const Eigen::Vector2i& start) {
  std::vector<bool> seen(free.size(), false);
  std::deque<Eigen::Vector2i> queue{start};
  seen[grid.index(start.x(), start.y())] = true;
  std::size_t count = 0;
  while (!queue.empty()) {
    const Eigen::Vector2i c = queue.front();
    queue.pop_front();
    ++count;
    for (const Eigen::Vector2i& d : {Eigen::Vector2i(1, 0), Eigen::Vector2i(-1, 0),
                                     Eigen::Vector2i(0, 1), Eigen::Vector2i(0, -1)}) {
      const Eigen::Vector2i n = c + d;
      if (!grid.inside(n.x(), n.y())) continue;
      const std::size_t i = grid.index(n.x(), n.y());
      if (free[i] && !seen[i]) {
        seen[i] = true;
        queue.push_back(n);
      }
    }
  }
  return static_cast<double>(count) * grid.resolution * grid.resolution;
}

}  // namespace

FaceChoice face_choice(const std::string& name) {
  if (name == "auto") return FaceChoice::kAuto;
  if (name == "left") return FaceChoice::kLeft;
  if (name == "right") return FaceChoice::kRight;
  throw BimError("unknown face '" + name + "' (expected auto, left or right)");
}

WallGoal wall_goal(const BimModel& model, const OccupancyGrid& grid,
                   const std::string& wall_global_id, double s, double h, double standoff,
                   double robot_radius, const GoalOptions& options) {
  const Element& wall = model.element(wall_global_id);
  const std::string what = "wall '" + wall_global_id + "'";
  if (wall.category != Category::kWall) {
    throw BimError("element '" + wall_global_id + "' is an " + wall.ifc_type + ", not a wall");
  }
  if (!(robot_radius > 0)) throw BimError("robot radius " + fmt(robot_radius) + " m: must be > 0");
  if (!(standoff > 0)) throw BimError("standoff " + fmt(standoff) + " m: must be > 0");
  const WallGeometry g = wall_geometry(wall);
  const Storey& storey = model.storey(wall.storey);
  if (!(s >= 0 && s <= g.length())) {
    throw BimError("s = " + fmt(s) + " m is off " + what + ": its axis is " + fmt(g.length()) +
                   " m long (0 .. " + fmt(g.length()) + ")");
  }
  const double z = storey.elevation + h;
  if (!(z >= g.z_min && z <= g.z_max)) {
    throw BimError("h = " + fmt(h) + " m is off " + what + ": it spans " +
                   fmt(g.z_min - storey.elevation) + " .. " + fmt(g.z_max - storey.elevation) +
                   " m above storey '" + storey.name + "'");
  }
  const Eigen::Vector2d d = g.direction();
  const Eigen::Vector2d on_axis = g.start + s * d;
  const Eigen::Vector2d n0 = g.faces[0].normal;
  const double reach = g.thickness / 2 + 0.05;
  const Eigen::Vector3d p(on_axis.x() + n0.x() * reach, on_axis.y() + n0.y() * reach, z);
  const Eigen::Vector3d q(on_axis.x() - n0.x() * reach, on_axis.y() - n0.y() * reach, z);
  if (!has_material(wall.mesh, p, q)) {
    std::string filler;
    for (const auto& e : model.elements) {
      if (e.host != wall_global_id || e.bounds.isEmpty()) continue;
      const Eigen::Vector3d pt(on_axis.x(), on_axis.y(), z);
      if (e.bounds.exteriorDistance(pt) < g.thickness / 2 + 0.05) {
        filler = " (" + e.ifc_type + " '" + e.global_id + "'" +
                 (e.name.empty() ? "" : " \"" + e.name + "\"") + ")";
        break;
      }
    }
    throw BimError("s = " + fmt(s) + " m, h = " + fmt(h) + " m on " + what + " is on an opening" +
                   (filler.empty() ? " (no material there)" : filler));
  }

  const std::vector<bool> free = free_space(grid, robot_radius);
  struct Candidate {
    int face;
    Eigen::Vector2d base;
    double area;
  };
  std::vector<Candidate> ok;
  std::string reasons;
  for (int k = 0; k < 2; ++k) {
    if ((options.face == FaceChoice::kLeft && k != 0) ||
        (options.face == FaceChoice::kRight && k != 1))
      continue;
    const Eigen::Vector2d n = g.faces[static_cast<std::size_t>(k)].normal;
    const Eigen::Vector2d base = on_axis + n * (g.thickness / 2 + standoff);
    const std::string name = k == 0 ? "left face" : "right face";
    const Eigen::Vector2i cell = grid.cell_of(base);
    std::string why;
    if (!grid.inside(cell.x(), cell.y())) {
      why = "the base pose (" + fmt(base.x()) + ", " + fmt(base.y()) + ") is outside the map";
    } else {
      // The exact disc at `base` (not at its cell's centre) must be free.
      const int m = static_cast<int>(std::ceil(robot_radius / grid.resolution)) + 1;
      for (int dy = -m; dy <= m && why.empty(); ++dy) {
        for (int dx = -m; dx <= m && why.empty(); ++dx) {
          const int c = cell.x() + dx;
          const int r = cell.y() + dy;
          const Eigen::Vector2d lo = grid.origin + grid.resolution * Eigen::Vector2d(c, r);
          const Eigen::Vector2d closest =
              base.cwiseMax(lo).cwiseMin(lo + Eigen::Vector2d::Constant(grid.resolution));
          if ((closest - base).norm() >= robot_radius) continue;
          if (!grid.inside(c, r)) {
            why = "the robot (radius " + fmt(robot_radius, 2) + " m) at (" + fmt(base.x()) + ", " +
                  fmt(base.y()) + ") reaches beyond the map";
          } else if (grid.at(c, r) != OccupancyGrid::kFree) {
            const Eigen::Vector2d at = grid.center_of(c, r);
            why = "the robot (radius " + fmt(robot_radius, 2) + " m) at (" + fmt(base.x()) + ", " +
                  fmt(base.y()) + ") overlaps the " +
                  (grid.at(c, r) == OccupancyGrid::kOccupied ? "occupied" : "unknown") +
                  " cell at (" + fmt(at.x()) + ", " + fmt(at.y()) + ")";
          }
        }
      }
      if (why.empty()) {
        if (!free[grid.index(cell.x(), cell.y())]) {
          why = "the base pose's cell is not in the robot's free space";
        } else {
          const double area = region_area(grid, free, cell);
          if (area < options.min_free_area) {
            why = "the base pose lies in a free region of only " + fmt(area, 2) + " m^2 (< " +
                  fmt(options.min_free_area, 2) + " m^2: not reachable)";
          } else {
            ok.push_back({k, base, area});
          }
        }
      }
    }
    if (!why.empty()) reasons += (reasons.empty() ? "" : "; ") + name + ": " + why;
  }
  if (ok.empty()) {
    throw BimError("no face of " + what + " is reachable at s = " + fmt(s) + " m, h = " + fmt(h) +
                   " m (standoff " + fmt(standoff, 2) + " m): " + reasons);
  }
  const Candidate& best = ok.size() == 2 && ok[1].area > ok[0].area ? ok[1] : ok[0];
  const Eigen::Vector2d n = g.faces[static_cast<std::size_t>(best.face)].normal;
  const Eigen::Vector3d nz(n.x(), n.y(), 0);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(nz);
  WallGoal goal;
  Eigen::Matrix3d rot;
  rot.col(0) = x;
  rot.col(1) = nz.cross(x);
  rot.col(2) = nz;
  goal.area_frame.linear() = rot;
  const Eigen::Vector2d on_face = on_axis + n * (g.thickness / 2);
  goal.area_frame.translation() = Eigen::Vector3d(on_face.x(), on_face.y(), z);
  goal.base_pose = Eigen::Vector3d(best.base.x(), best.base.y(), std::atan2(-n.y(), -n.x()));
  goal.face = best.face;
  goal.storey = storey.name;
  goal.free_area = best.area;
  return goal;
}

}  // namespace concert::bim
