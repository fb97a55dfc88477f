#include "concert/world/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace concert::world {
namespace {

Eigen::Vector3d local_axis(Face face) {
  switch (face) {
    case Face::kPlusX:
      return Eigen::Vector3d::UnitX();
    case Face::kMinusX:
      return -Eigen::Vector3d::UnitX();
    case Face::kPlusY:
      return Eigen::Vector3d::UnitY();
    case Face::kMinusY:
      break;
  }
  return -Eigen::Vector3d::UnitY();
}

bool along_x(Face face) { return face == Face::kPlusX || face == Face::kMinusX; }

double cosine_bump(const SurfaceFeature& f, double u, double z) {
  const double r = std::hypot(u - f.at.x(), z - f.at.y());
  return r < f.radius ? f.height * 0.5 * (1.0 + std::cos(M_PI * r / f.radius)) : 0.0;
}

// Position along the polyline start -> waypoints (-> start if closed) at arc length s.
Eigen::Vector2d along(const WorldShape& o, double s, bool closed) {
  const auto& w = o.path->waypoints;
  Eigen::Vector2d from = o.position.head<2>();
  const std::size_t n = w.size() + (closed ? 1 : 0);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d to = i < w.size() ? w[i] : Eigen::Vector2d(o.position.head<2>());
    const double len = (to - from).norm();
    if (s <= len && len > 0.0) {
      return from + (to - from) * (s / len);
    }
    s -= len;
    from = to;
  }
  return from;
}

}  // namespace

const WorldShape& find_wall(const World& world, const std::string& name) {
  for (const auto& w : world.walls) {
    if (w.name == name) {
      return w;
    }
  }
  throw WorldError("no wall named '" + name + "'");
}

Eigen::Isometry3d face_frame(const WorldShape& wall, Face face) {
  const Eigen::Matrix3d yaw =
      Eigen::AngleAxisd(wall.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d axis = local_axis(face);
  const double half_depth = 0.5 * (along_x(face) ? wall.size.x() : wall.size.y());
  const Eigen::Vector3d n = yaw * axis;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.linear().col(0) = up.cross(n);
  frame.linear().col(1) = up;
  frame.linear().col(2) = n;
  frame.translation() = wall.position + half_depth * n;
  return frame;
}

Eigen::Vector2d face_size(const WorldShape& wall, Face face) {
  return {along_x(face) ? wall.size.y() : wall.size.x(), wall.size.z()};
}

Eigen::Vector3d face_point(const WorldShape& wall, Face face, const Eigen::Vector2d& at,
                           double offset) {
  return face_frame(wall, face) * Eigen::Vector3d(at.x(), at.y() - wall.position.z(), offset);
}

std::vector<MarkTruth> mark_truth(const World& world) {
  std::vector<MarkTruth> out;
  for (const auto& m : world.marks) {
    const WorldShape& wall = find_wall(world, m.wall);
    const Eigen::Isometry3d frame = face_frame(wall, m.face);
    MarkTruth t;
    t.name = m.name;
    t.type = m.type;
    t.centre = face_point(wall, m.face, m.at, kMarkStandoff);
    t.normal = frame.linear().col(2);
    t.right = frame.linear().col(0);
    if (m.type == Mark::Type::kBlob) {
      t.diameter = m.diameter;
    } else {
      t.size = m.size;
      t.dictionary = m.dictionary;
      t.id = m.id;
      t.angle = m.angle;
      const Eigen::Rotation2Dd rot(m.angle);
      const double h = 0.5 * m.size;
      const std::array<Eigen::Vector2d, 4> upright{Eigen::Vector2d(-h, h), Eigen::Vector2d(h, h),
                                                   Eigen::Vector2d(h, -h), Eigen::Vector2d(-h, -h)};
      for (std::size_t k = 0; k < 4; ++k) {
        const Eigen::Vector2d c = rot * upright[k];
        t.corners[k] = t.centre + c.x() * t.right + c.y() * Eigen::Vector3d::UnitZ();
      }
    }
    out.push_back(std::move(t));
  }
  return out;
}

double surface_height(const Surface& surface, double u, double z) {
  double h = 0.0;
  for (const auto& b : surface.bumps) {
    h += cosine_bump(b, u, z);
  }
  for (const auto& hole : surface.holes) {
    h -= cosine_bump(hole, u, z);
  }
  return h;
}

Eigen::Vector3d surface_point(const World& world, const Surface& surface, double u, double z) {
  return face_point(find_wall(world, surface.wall), surface.face, {u, z},
                    surface.thickness + surface_height(surface, u, z));
}

double path_length(const WorldShape& obstacle) {
  if (!obstacle.path || obstacle.path->waypoints.empty()) {
    return 0.0;
  }
  const auto& w = obstacle.path->waypoints;
  double length = (w.front() - obstacle.position.head<2>()).norm();
  for (std::size_t i = 1; i < w.size(); ++i) {
    length += (w[i] - w[i - 1]).norm();
  }
  if (obstacle.path->mode == ObstaclePath::Mode::kLoop) {
    length += (obstacle.position.head<2>() - w.back()).norm();
  }
  return length;
}

Eigen::Vector3d obstacle_position(const WorldShape& obstacle, double t) {
  const double length = path_length(obstacle);
  if (length <= 0.0 || t <= 0.0) {
    return obstacle.position;
  }
  const ObstaclePath& p = *obstacle.path;
  double s = p.speed * t;
  switch (p.mode) {
    case ObstaclePath::Mode::kLoop:
      s = std::fmod(s, length);
      break;
    case ObstaclePath::Mode::kPingPong:
      s = std::fmod(s, 2.0 * length);
      s = s > length ? 2.0 * length - s : s;
      break;
    case ObstaclePath::Mode::kOnce:
      s = std::min(s, length);
      break;
  }
  const Eigen::Vector2d xy = along(obstacle, s, p.mode == ObstaclePath::Mode::kLoop);
  return {xy.x(), xy.y(), obstacle.position.z()};
}

}  // namespace concert::world
