#include "world_mjcf.hpp"

#include <sstream>

#include "mjcf_text.hpp"

namespace concert::sim {

using mjcf::num;
using mjcf::vec;
using world::WorldShape;

WorldMjcf world_mjcf(const world::World& world) {
  std::ostringstream xml;
  if (world.floor) {
    xml << "<geom name=\"floor\" type=\"plane\" size=\"100 100 0.1\" pos=\"0 0 " << num(world.floor_height)
        << "\" contype=\"0\" conaffinity=\"1\" friction=\"" << num(world.floor_friction) << " 0.005 0.0001\"/>\n";
  }
  auto shape = [&](const WorldShape& s) {
    const std::string where = "pos=\"" + vec(s.position.x(), s.position.y(), s.position.z()) + "\" euler=\"0 0 " +
                              num(s.yaw) + "\" contype=\"0\" conaffinity=\"1\" friction=\"" + num(s.friction) +
                              " 0.005 0.0001\"";
    if (s.type == WorldShape::Type::kBox) {
      xml << "<geom name=\"" << s.name << "\" type=\"box\" size=\"" << vec(s.size.x() / 2, s.size.y() / 2, s.size.z() / 2)
          << "\" " << where << "/>\n";
    } else {
      xml << "<geom name=\"" << s.name << "\" type=\"cylinder\" size=\"" << num(s.size.x()) << " "
          << num(s.size.z() / 2) << "\" " << where << "/>\n";
    }
  };
  for (const auto& w : world.walls) {
    shape(w);
  }
  for (const auto& o : world.obstacles) {
    shape(o);
  }
  return {"", xml.str()};
}

}  // namespace concert::sim
