#include "concert/world/world_dds.hpp"

#include <chrono>

namespace concert::world {
namespace {

msg::WorldPoint2 point(const Eigen::Vector2d& v) {
  msg::WorldPoint2 p;
  p.a(v.x());
  p.b(v.y());
  return p;
}

Eigen::Vector2d point(const msg::WorldPoint2& p) { return {p.a(), p.b()}; }

// The IDL enums list the faces, path modes and shape types in the order of the C++ enums.
static_assert(static_cast<int>(Face::kMinusY) == msg::WORLD_FACE_MINUS_Y);
static_assert(static_cast<int>(ObstaclePath::Mode::kOnce) == msg::WORLD_PATH_ONCE);
msg::WorldFace face(Face f) { return static_cast<msg::WorldFace>(static_cast<int>(f)); }
Face face(msg::WorldFace f) {
  if (static_cast<int>(f) < 0 || static_cast<int>(f) > msg::WORLD_FACE_MINUS_Y) {
    throw WorldError("world message: unknown face value " + std::to_string(static_cast<int>(f)));
  }
  return static_cast<Face>(static_cast<int>(f));
}

msg::WorldShape to_msg(const WorldShape& s) {
  msg::WorldShape out;
  out.name(s.name);
  out.type(s.type == WorldShape::Type::kCylinder ? msg::WORLD_CYLINDER : msg::WORLD_BOX);
  out.size({s.size.x(), s.size.y(), s.size.z()});
  out.position({s.position.x(), s.position.y(), s.position.z()});
  out.yaw(s.yaw);
  out.friction(s.friction);
  if (s.path) {
    for (const auto& w : s.path->waypoints) {
      out.waypoints().push_back(point(w));
    }
    out.path_speed(s.path->speed);
    out.path_mode(static_cast<msg::WorldPathMode>(static_cast<int>(s.path->mode)));
  }
  return out;
}

WorldShape from_msg(const msg::WorldShape& s) {
  WorldShape out;
  out.name = s.name();
  out.type = s.type() == msg::WORLD_CYLINDER ? WorldShape::Type::kCylinder : WorldShape::Type::kBox;
  out.size = {s.size()[0], s.size()[1], s.size()[2]};
  out.position = {s.position()[0], s.position()[1], s.position()[2]};
  out.yaw = s.yaw();
  out.friction = s.friction();
  if (!s.waypoints().empty()) {
    ObstaclePath path;
    for (const auto& w : s.waypoints()) {
      path.waypoints.push_back(point(w));
    }
    path.speed = s.path_speed();
    if (static_cast<int>(s.path_mode()) < 0 ||
        static_cast<int>(s.path_mode()) > msg::WORLD_PATH_ONCE) {
      throw WorldError("world message: obstacle '" + s.name() + "': unknown path mode value " +
                       std::to_string(static_cast<int>(s.path_mode())));
    }
    path.mode = static_cast<ObstaclePath::Mode>(static_cast<int>(s.path_mode()));
    out.path = std::move(path);
  }
  return out;
}

msg::WorldMark to_msg(const Mark& m) {
  msg::WorldMark out;
  out.name(m.name);
  out.type(m.type == Mark::Type::kAruco ? msg::WORLD_MARK_ARUCO : msg::WORLD_MARK_BLOB);
  out.wall(m.wall);
  out.face(face(m.face));
  out.at(point(m.at));
  out.diameter(m.diameter);
  out.rgba({m.rgba[0], m.rgba[1], m.rgba[2], m.rgba[3]});
  out.size(m.size);
  out.dictionary(m.dictionary);
  out.id(m.id);
  out.angle(m.angle);
  return out;
}

Mark from_msg(const msg::WorldMark& m) {
  Mark out;
  out.name = m.name();
  out.type = m.type() == msg::WORLD_MARK_ARUCO ? Mark::Type::kAruco : Mark::Type::kBlob;
  out.wall = m.wall();
  out.face = face(m.face());
  out.at = point(m.at());
  out.diameter = m.diameter();
  out.rgba = {m.rgba()[0], m.rgba()[1], m.rgba()[2], m.rgba()[3]};
  out.size = m.size();
  out.dictionary = m.dictionary();
  out.id = m.id();
  out.angle = m.angle();
  return out;
}

std::vector<msg::WorldSurfaceFeature> to_msg(const std::vector<SurfaceFeature>& features) {
  std::vector<msg::WorldSurfaceFeature> out;
  for (const auto& f : features) {
    msg::WorldSurfaceFeature m;
    m.at(point(f.at));
    m.radius(f.radius);
    m.height(f.height);
    out.push_back(m);
  }
  return out;
}

std::vector<SurfaceFeature> from_msg(const std::vector<msg::WorldSurfaceFeature>& features) {
  std::vector<SurfaceFeature> out;
  for (const auto& f : features) {
    out.push_back({point(f.at()), f.radius(), f.height()});
  }
  return out;
}

msg::WorldSurface to_msg(const Surface& s) {
  msg::WorldSurface out;
  out.name(s.name);
  out.wall(s.wall);
  out.face(face(s.face));
  out.at(point(s.at));
  out.size(point(s.size));
  out.thickness(s.thickness);
  out.resolution(s.resolution);
  out.bumps(to_msg(s.bumps));
  out.holes(to_msg(s.holes));
  return out;
}

Surface from_msg(const msg::WorldSurface& s) {
  Surface out;
  out.name = s.name();
  out.wall = s.wall();
  out.face = face(s.face());
  out.at = point(s.at());
  out.size = point(s.size());
  out.thickness = s.thickness();
  out.resolution = s.resolution();
  out.bumps = from_msg(s.bumps());
  out.holes = from_msg(s.holes());
  return out;
}

}  // namespace

msg::World to_msg(const World& world, std::uint32_t version, const std::string& source) {
  msg::World out;
  out.version(version);
  out.stamp_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(
                   std::chrono::system_clock::now().time_since_epoch())
                   .count());
  out.source(source);
  out.floor(world.floor);
  out.floor_height(world.floor_height);
  out.floor_friction(world.floor_friction);
  for (const auto& w : world.walls) {
    out.walls().push_back(to_msg(w));
  }
  for (const auto& o : world.obstacles) {
    out.obstacles().push_back(to_msg(o));
  }
  for (const auto& m : world.marks) {
    out.marks().push_back(to_msg(m));
  }
  for (const auto& s : world.surfaces) {
    out.surfaces().push_back(to_msg(s));
  }
  return out;
}

World from_msg(const msg::World& message) {
  World out;
  out.floor = message.floor();
  out.floor_height = message.floor_height();
  out.floor_friction = message.floor_friction();
  for (const auto& w : message.walls()) {
    out.walls.push_back(from_msg(w));
  }
  for (const auto& o : message.obstacles()) {
    out.obstacles.push_back(from_msg(o));
  }
  for (const auto& m : message.marks()) {
    out.marks.push_back(from_msg(m));
  }
  for (const auto& s : message.surfaces()) {
    out.surfaces.push_back(from_msg(s));
  }
  validate_world(out, "world message '" + message.source() + "'");
  return out;
}

}  // namespace concert::world
