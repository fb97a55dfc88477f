#include "concert/world/world_dds.hpp"

#include <chrono>

namespace concert::world {
namespace {

msg::WorldShape to_msg(const WorldShape& s) {
  msg::WorldShape out;
  out.name(s.name);
  out.type(s.type == WorldShape::Type::kCylinder ? msg::WORLD_CYLINDER : msg::WORLD_BOX);
  out.size({s.size.x(), s.size.y(), s.size.z()});
  out.position({s.position.x(), s.position.y(), s.position.z()});
  out.yaw(s.yaw);
  out.friction(s.friction);
  return out;
}

WorldShape from_msg(const msg::WorldShape& s, const std::string& field) {
  WorldShape out;
  out.name = s.name();
  out.type = s.type() == msg::WORLD_CYLINDER ? WorldShape::Type::kCylinder : WorldShape::Type::kBox;
  out.size = {s.size()[0], s.size()[1], s.size()[2]};
  out.position = {s.position()[0], s.position()[1], s.position()[2]};
  out.yaw = s.yaw();
  out.friction = s.friction();
  if (out.size.x() <= 0.0 || out.size.z() <= 0.0 || (out.type == WorldShape::Type::kBox && out.size.y() <= 0.0)) {
    throw WorldError("world message: " + field + " '" + out.name + "': dimensions must be positive");
  }
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
  return out;
}

World from_msg(const msg::World& message) {
  World out;
  out.floor = message.floor();
  out.floor_height = message.floor_height();
  out.floor_friction = message.floor_friction();
  for (std::size_t i = 0; i < message.walls().size(); ++i) {
    out.walls.push_back(from_msg(message.walls()[i], "walls[" + std::to_string(i) + "]"));
  }
  for (std::size_t i = 0; i < message.obstacles().size(); ++i) {
    out.obstacles.push_back(from_msg(message.obstacles()[i], "obstacles[" + std::to_string(i) + "]"));
  }
  return out;
}

}  // namespace concert::world
