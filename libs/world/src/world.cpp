#include "concert/world/world.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <set>
#include <sstream>

namespace concert::world {
namespace {

struct Ctx {
  const std::string& source;
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw WorldError("world file '" + source + "': " + field + ": " + what);
  }
};

double number(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    ctx.fail(field, "expected a number");
  }
}

Eigen::Vector3d vec3(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  if (!node.IsSequence() || node.size() != 3) {
    ctx.fail(field, "expected a list of 3 numbers");
  }
  return {number(ctx, node[0], field + "[0]"), number(ctx, node[1], field + "[1]"),
          number(ctx, node[2], field + "[2]")};
}

WorldShape shape(const Ctx& ctx, const YAML::Node& node, const std::string& field, bool allow_cylinder) {
  if (!node.IsMap()) {
    ctx.fail(field, "expected a map with name, size, position");
  }
  static const std::set<std::string> kKeys{"name", "shape", "size", "radius", "height", "position", "yaw", "friction"};
  for (const auto& kv : node) {
    const auto key = kv.first.as<std::string>();
    if (kKeys.count(key) == 0) {
      ctx.fail(field + "." + key, "unknown key");
    }
  }
  WorldShape s;
  if (!node["name"]) {
    ctx.fail(field + ".name", "missing");
  }
  s.name = node["name"].as<std::string>();
  const std::string type = node["shape"] ? node["shape"].as<std::string>() : "box";
  if (type == "box") {
    if (!node["size"]) {
      ctx.fail(field + ".size", "missing (box needs [x, y, z] full extents)");
    }
    s.size = vec3(ctx, node["size"], field + ".size");
  } else if (type == "cylinder" && allow_cylinder) {
    s.type = WorldShape::Type::kCylinder;
    if (!node["radius"] || !node["height"]) {
      ctx.fail(field, "cylinder needs radius and height");
    }
    s.size = {number(ctx, node["radius"], field + ".radius"), 0.0, number(ctx, node["height"], field + ".height")};
  } else {
    ctx.fail(field + ".shape", "unknown shape '" + type + "' (walls: box; obstacles: box or cylinder)");
  }
  if (s.size.x() <= 0.0 || s.size.z() <= 0.0 || (s.type == WorldShape::Type::kBox && s.size.y() <= 0.0)) {
    ctx.fail(field + ".size", "dimensions must be positive");
  }
  if (!node["position"]) {
    ctx.fail(field + ".position", "missing");
  }
  s.position = vec3(ctx, node["position"], field + ".position");
  if (node["yaw"]) {
    s.yaw = number(ctx, node["yaw"], field + ".yaw");
  }
  if (node["friction"]) {
    s.friction = number(ctx, node["friction"], field + ".friction");
    if (s.friction < 0.0) {
      ctx.fail(field + ".friction", "must not be negative");
    }
  }
  return s;
}

}  // namespace

World parse_world_yaml(const std::string& text, const std::string& source) {
  const Ctx ctx{source};
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw WorldError("world file '" + source + "': YAML error at line " + std::to_string(e.mark.line + 1) + ": " +
                     e.msg);
  }
  World world;
  if (root.IsNull()) {
    return world;
  }
  if (!root.IsMap()) {
    ctx.fail("top level", "expected a map with floor, walls, obstacles");
  }
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (key != "floor" && key != "walls" && key != "obstacles") {
      ctx.fail(key, "unknown key (expected floor, walls, obstacles)");
    }
  }
  if (const auto floor = root["floor"]) {
    if (floor.IsScalar()) {
      world.floor = floor.as<bool>();
    } else {
      if (floor["enabled"]) {
        world.floor = floor["enabled"].as<bool>();
      }
      if (floor["height"]) {
        world.floor_height = number(ctx, floor["height"], "floor.height");
      }
      if (floor["friction"]) {
        world.floor_friction = number(ctx, floor["friction"], "floor.friction");
      }
    }
  }
  std::set<std::string> names;
  auto add_all = [&](const char* key, std::vector<WorldShape>& out, bool allow_cylinder) {
    const auto list = root[key];
    if (!list) {
      return;
    }
    if (!list.IsSequence()) {
      ctx.fail(key, "expected a list");
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string field = std::string(key) + "[" + std::to_string(i) + "]";
      out.push_back(shape(ctx, list[i], field, allow_cylinder));
      if (!names.insert(out.back().name).second) {
        ctx.fail(field + ".name", "duplicate name '" + out.back().name + "'");
      }
    }
  };
  add_all("walls", world.walls, false);
  add_all("obstacles", world.obstacles, true);
  return world;
}

World load_world_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw WorldError("cannot open world file '" + path + "'");
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_world_yaml(buffer.str(), path);
}

}  // namespace concert::world
