#include "concert/world/world.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "concert/world/aruco.hpp"
#include "concert/world/geometry.hpp"

namespace concert::world {
namespace {

struct Ctx {
  const std::string& source;
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw WorldError("world file '" + source + "': " + field + ": " + what);
  }
};

double number(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  double v = 0.0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    ctx.fail(field, "expected a number");
  }
  if (!std::isfinite(v)) {
    ctx.fail(field, "expected a finite number");
  }
  return v;
}

std::string text(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  if (!node.IsScalar()) {
    ctx.fail(field, "expected a string");
  }
  return node.as<std::string>();
}

bool boolean(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  try {
    return node.as<bool>();
  } catch (const YAML::Exception&) {
    ctx.fail(field, "expected true or false");
  }
}

/// The text of a mapping key (a list or a mapping as a key is refused).
std::string key_text(const Ctx& ctx, const YAML::Node& key, const std::string& field) {
  if (!key.IsScalar()) ctx.fail(field, "a key that is not a name");
  return key.Scalar();
}

int integer(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  try {
    return node.as<int>();
  } catch (const YAML::Exception&) {
    ctx.fail(field, "expected an integer");
  }
}

template <int N>
Eigen::Matrix<double, N, 1> vec(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  if (!node.IsSequence() || node.size() != N) {
    ctx.fail(field, "expected a list of " + std::to_string(N) + " numbers");
  }
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) {
    v(i) = number(ctx, node[static_cast<std::size_t>(i)], field + "[" + std::to_string(i) + "]");
  }
  return v;
}

void only_keys(const Ctx& ctx, const YAML::Node& node, const std::string& field,
               const std::set<std::string>& keys, const std::string& what) {
  if (!node.IsMap()) {
    ctx.fail(field, "expected a map with " + what);
  }
  for (const auto& kv : node) {
    const std::string key = key_text(ctx, kv.first, field);
    if (keys.count(key) == 0) {
      ctx.fail(field + "." + key, "unknown key (expected " + what + ")");
    }
  }
}

YAML::Node required(const Ctx& ctx, const YAML::Node& node, const std::string& field,
                    const std::string& key, const std::string& why = "") {
  const YAML::Node child = node[key];
  if (!child) {
    ctx.fail(field + "." + key, "missing" + (why.empty() ? "" : " (" + why + ")"));
  }
  return child;
}

ObstaclePath path(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  only_keys(ctx, node, field, {"waypoints", "speed", "mode"}, "waypoints, speed, mode");
  ObstaclePath p;
  const YAML::Node points = required(ctx, node, field, "waypoints", "a list of [x, y] [m]");
  if (!points.IsSequence()) {
    ctx.fail(field + ".waypoints", "expected a list of [x, y]");
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    p.waypoints.push_back(vec<2>(ctx, points[i], field + ".waypoints[" + std::to_string(i) + "]"));
  }
  p.speed = number(ctx, required(ctx, node, field, "speed", "[m/s]"), field + ".speed");
  if (node["mode"]) {
    const std::string mode = text(ctx, node["mode"], field + ".mode");
    if (mode == "loop") {
      p.mode = ObstaclePath::Mode::kLoop;
    } else if (mode == "pingpong") {
      p.mode = ObstaclePath::Mode::kPingPong;
    } else if (mode == "once") {
      p.mode = ObstaclePath::Mode::kOnce;
    } else {
      ctx.fail(field + ".mode", "unknown mode '" + mode + "' (expected loop, pingpong or once)");
    }
  }
  return p;
}

WorldShape shape(const Ctx& ctx, const YAML::Node& node, const std::string& field, bool obstacle) {
  static const std::set<std::string> kWallKeys{"name",   "shape",    "size", "radius",
                                               "height", "position", "yaw",  "friction"};
  static const std::set<std::string> kObstacleKeys{
      "name", "shape", "size", "radius", "height", "position", "yaw", "friction", "path"};
  only_keys(ctx, node, field, obstacle ? kObstacleKeys : kWallKeys,
            obstacle ? "name, shape, size|radius+height, position, yaw, friction, path"
                     : "name, size, position, yaw, friction");
  WorldShape s;
  s.name = text(ctx, required(ctx, node, field, "name"), field + ".name");
  const std::string type = node["shape"] ? text(ctx, node["shape"], field + ".shape") : "box";
  if (type == "box") {
    s.size = vec<3>(ctx, required(ctx, node, field, "size", "box needs [x, y, z] full extents"),
                    field + ".size");
  } else if (type == "cylinder" && obstacle) {
    s.type = WorldShape::Type::kCylinder;
    if (!node["radius"] || !node["height"]) {
      ctx.fail(field, "cylinder needs radius and height");
    }
    s.size = {number(ctx, node["radius"], field + ".radius"), 0.0,
              number(ctx, node["height"], field + ".height")};
  } else {
    ctx.fail(field + ".shape",
             "unknown shape '" + type + "' (walls: box; obstacles: box or cylinder)");
  }
  s.position = vec<3>(ctx, required(ctx, node, field, "position"), field + ".position");
  if (node["yaw"]) {
    s.yaw = number(ctx, node["yaw"], field + ".yaw");
  }
  if (node["friction"]) {
    s.friction = number(ctx, node["friction"], field + ".friction");
  }
  if (node["path"]) {
    s.path = path(ctx, node["path"], field + ".path");
  }
  return s;
}

Face face(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  const std::string f = text(ctx, node, field);
  for (const Face candidate : {Face::kPlusX, Face::kMinusX, Face::kPlusY, Face::kMinusY}) {
    if (f == to_string(candidate)) {
      return candidate;
    }
  }
  ctx.fail(field,
           "unknown face '" + f + "' (expected +x, -x, +y or -y: the wall box's local axes)");
}

Mark mark(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  if (!node.IsMap()) {
    ctx.fail(field, "expected a map with type, name, wall, face, at, ...");
  }
  Mark m;
  const std::string type =
      text(ctx, required(ctx, node, field, "type", "blob or aruco"), field + ".type");
  if (type == "blob") {
    only_keys(ctx, node, field, {"type", "name", "wall", "face", "at", "diameter", "rgba"},
              "type, name, wall, face, at, diameter, rgba");
    m.type = Mark::Type::kBlob;
    m.diameter = number(ctx, required(ctx, node, field, "diameter", "[m]"), field + ".diameter");
    if (node["rgba"]) {
      m.rgba = vec<4>(ctx, node["rgba"], field + ".rgba");
    }
  } else if (type == "aruco") {
    only_keys(ctx, node, field,
              {"type", "name", "wall", "face", "at", "size", "dictionary", "id", "angle"},
              "type, name, wall, face, at, size, dictionary, id, angle");
    m.type = Mark::Type::kAruco;
    m.size = number(ctx, required(ctx, node, field, "size", "outer side [m]"), field + ".size");
    m.dictionary = text(ctx, required(ctx, node, field, "dictionary", "e.g. DICT_4X4_50"),
                        field + ".dictionary");
    m.id = integer(ctx, required(ctx, node, field, "id"), field + ".id");
    if (node["angle"]) {
      m.angle = number(ctx, node["angle"], field + ".angle");
    }
  } else {
    ctx.fail(field + ".type", "unknown mark type '" + type + "' (expected blob or aruco)");
  }
  m.name = text(ctx, required(ctx, node, field, "name"), field + ".name");
  m.wall = text(ctx, required(ctx, node, field, "wall"), field + ".wall");
  m.face = face(ctx, required(ctx, node, field, "face", "+x, -x, +y or -y"), field + ".face");
  m.at = vec<2>(ctx, required(ctx, node, field, "at", "[u, z] [m]"), field + ".at");
  return m;
}

std::vector<SurfaceFeature> features(const Ctx& ctx, const YAML::Node& node,
                                     const std::string& field, const char* height_key) {
  std::vector<SurfaceFeature> out;
  if (!node) {
    return out;
  }
  if (!node.IsSequence()) {
    ctx.fail(field, "expected a list");
  }
  const std::string keys = std::string("at, radius, ") + height_key;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    only_keys(ctx, node[i], f, {"at", "radius", height_key}, keys);
    SurfaceFeature feature;
    feature.at = vec<2>(ctx, required(ctx, node[i], f, "at", "[u, z] [m]"), f + ".at");
    feature.radius = number(ctx, required(ctx, node[i], f, "radius", "[m]"), f + ".radius");
    feature.height =
        number(ctx, required(ctx, node[i], f, height_key, "[m]"), f + "." + height_key);
    out.push_back(feature);
  }
  return out;
}

Surface surface(const Ctx& ctx, const YAML::Node& node, const std::string& field) {
  only_keys(ctx, node, field,
            {"name", "wall", "face", "at", "size", "thickness", "resolution", "bumps", "holes"},
            "name, wall, face, at, size, thickness, resolution, bumps, holes");
  Surface s;
  s.name = text(ctx, required(ctx, node, field, "name"), field + ".name");
  s.wall = text(ctx, required(ctx, node, field, "wall"), field + ".wall");
  s.face = face(ctx, required(ctx, node, field, "face", "+x, -x, +y or -y"), field + ".face");
  s.at = vec<2>(ctx, required(ctx, node, field, "at", "centre [u, z] [m]"), field + ".at");
  s.size = vec<2>(ctx, required(ctx, node, field, "size", "[width, height] [m]"), field + ".size");
  if (node["thickness"]) {
    s.thickness = number(ctx, node["thickness"], field + ".thickness");
  }
  if (node["resolution"]) {
    s.resolution = number(ctx, node["resolution"], field + ".resolution");
  }
  s.bumps = features(ctx, node["bumps"], field + ".bumps", "height");
  s.holes = features(ctx, node["holes"], field + ".holes", "depth");
  return s;
}

// --- validation -----------------------------------------------------------------------------

/// Where a mark or surface sits on a face, as an axis-aligned rectangle in [u, z] (or a disc).
struct Footprint {
  std::string field;  // e.g. marks[1]
  std::string name;
  Eigen::Vector2d centre;
  Eigen::Vector2d half;  // half extents along u and z
  bool disc{false};      // blob: a disc of radius half.x()
};

bool overlap(const Footprint& a, const Footprint& b) {
  if (a.disc && b.disc) {
    return (a.centre - b.centre).norm() < a.half.x() + b.half.x();
  }
  const Eigen::Vector2d d = (a.centre - b.centre).cwiseAbs();
  return d.x() < a.half.x() + b.half.x() && d.y() < a.half.y() + b.half.y();
}

struct Validator {
  const std::string& where;
  const World& world;
  std::map<std::string, std::vector<Footprint>> on_face;  // "wall face" -> footprints

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw WorldError(where + ": " + field + ": " + what);
  }

  void positive(double v, const std::string& field) const {
    if (!(v > 0.0) || !std::isfinite(v)) {
      fail(field, "must be positive (got " + std::to_string(v) + ")");
    }
  }

  void shape(const WorldShape& s, const std::string& field) const {
    if (s.size.x() <= 0.0 || s.size.z() <= 0.0 ||
        (s.type == WorldShape::Type::kBox && s.size.y() <= 0.0)) {
      fail(field + ".size", "dimensions must be positive");
    }
    if (s.friction < 0.0) {
      fail(field + ".friction", "must not be negative");
    }
    if (s.path) {
      if (s.path->waypoints.empty()) {
        fail(field + ".path.waypoints", "needs at least one waypoint");
      }
      positive(s.path->speed, field + ".path.speed");
    }
  }

  const WorldShape& wall(const std::string& name, const std::string& field) const {
    for (const auto& w : world.walls) {
      if (w.name == name) {
        return w;
      }
    }
    std::string all;
    for (const auto& w : world.walls) {
      all += (all.empty() ? "" : ", ") + w.name;
    }
    fail(field, "no wall named '" + name + "' (walls: " + (all.empty() ? "none" : all) + ")");
  }

  // The footprint must lie on the face; then it must not overlap what is already there.
  void place(const WorldShape& w, Face face, const Footprint& f) {
    const Eigen::Vector2d size = face_size(w, face);
    constexpr double kEps = 1e-9;
    const double bottom = w.position.z() - 0.5 * size.y(), top = w.position.z() + 0.5 * size.y();
    if (std::abs(f.centre.x()) + f.half.x() > 0.5 * size.x() + kEps ||
        f.centre.y() - f.half.y() < bottom - kEps || f.centre.y() + f.half.y() > top + kEps) {
      std::ostringstream why;
      why << "'" << f.name << "' is not entirely on face " << to_string(face) << " of wall '"
          << w.name << "' (it spans u " << f.centre.x() - f.half.x() << " .. "
          << f.centre.x() + f.half.x() << ", z " << f.centre.y() - f.half.y() << " .. "
          << f.centre.y() + f.half.y() << "; the face spans u " << -0.5 * size.x() << " .. "
          << 0.5 * size.x() << ", z " << bottom << " .. " << top << ") [m]";
      fail(f.field + ".at", why.str());
    }
    auto& placed = on_face[w.name + " " + to_string(face)];
    for (const auto& other : placed) {
      if (overlap(f, other)) {
        fail(f.field + ".at", "'" + f.name + "' overlaps " + other.field + " '" + other.name +
                                  "' on face " + to_string(face) + " of wall '" + w.name + "'");
      }
    }
    placed.push_back(f);
  }

  void mark(const Mark& m, const std::string& field) {
    const WorldShape& w = wall(m.wall, field + ".wall");
    Footprint f{field, m.name, m.at, {0, 0}, m.type == Mark::Type::kBlob};
    if (m.type == Mark::Type::kBlob) {
      positive(m.diameter, field + ".diameter");
      if ((m.rgba.array() < 0.0).any() || (m.rgba.array() > 1.0).any()) {
        fail(field + ".rgba", "components must be within 0..1");
      }
      f.half.setConstant(0.5 * m.diameter);
    } else {
      positive(m.size, field + ".size");
      int count = 0;
      try {
        count = aruco_dictionary_size(m.dictionary);  // names the accepted ones if unknown
      } catch (const WorldError& e) {
        fail(field + ".dictionary", e.what());
      }
      if (m.id < 0 || m.id >= count) {
        fail(field + ".id", "id " + std::to_string(m.id) + " is not in " + m.dictionary +
                                " (ids 0.." + std::to_string(count - 1) + ")");
      }
      // The rotated square's bounding box.
      f.half.setConstant(0.5 * m.size *
                         (std::abs(std::cos(m.angle)) + std::abs(std::sin(m.angle))));
    }
    place(w, m.face, f);
  }

  void surface(const Surface& s, const std::string& field) {
    const WorldShape& w = wall(s.wall, field + ".wall");
    positive(s.size.x(), field + ".size[0]");
    positive(s.size.y(), field + ".size[1]");
    positive(s.thickness, field + ".thickness");
    positive(s.resolution, field + ".resolution");
    constexpr double kMaxCells = 2000.0;
    if (s.size.maxCoeff() / s.resolution > kMaxCells) {
      fail(field + ".resolution", "too fine: more than 2000 grid cells along a side of the panel");
    }
    if (s.resolution > 0.5 * s.size.minCoeff()) {
      fail(field + ".resolution", "too coarse: less than 2 grid cells along a side of the panel");
    }
    std::vector<Footprint> features;
    auto feature = [&](const SurfaceFeature& f, const std::string& ff, const char* height_key) {
      positive(f.radius, ff + ".radius");
      positive(f.height, ff + "." + height_key);
      const Eigen::Vector2d d = (f.at - s.at).cwiseAbs();
      if (d.x() + f.radius > 0.5 * s.size.x() + 1e-9 ||
          d.y() + f.radius > 0.5 * s.size.y() + 1e-9) {
        fail(ff + ".at",
             "not entirely on the panel '" + s.name + "' (centre and radius must stay inside it)");
      }
      const Footprint fp{ff, "", f.at, {f.radius, f.radius}, true};
      for (const auto& other : features) {
        if (overlap(fp, other)) {
          fail(ff + ".at", "overlaps " + other.field + " (bumps and holes must not overlap)");
        }
      }
      features.push_back(fp);
    };
    for (std::size_t i = 0; i < s.bumps.size(); ++i) {
      feature(s.bumps[i], field + ".bumps[" + std::to_string(i) + "]", "height");
    }
    for (std::size_t i = 0; i < s.holes.size(); ++i) {
      const std::string hf = field + ".holes[" + std::to_string(i) + "]";
      feature(s.holes[i], hf, "depth");
      if (s.holes[i].height >= s.thickness) {
        fail(hf + ".depth", "a hole must be shallower than the layer (depth " +
                                std::to_string(s.holes[i].height) + " m, thickness " +
                                std::to_string(s.thickness) + " m)");
      }
    }
    place(w, s.face, {field, s.name, s.at, 0.5 * s.size, false});
  }
};

}  // namespace

std::string to_string(Face face) {
  switch (face) {
    case Face::kPlusX:
      return "+x";
    case Face::kMinusX:
      return "-x";
    case Face::kPlusY:
      return "+y";
    case Face::kMinusY:
      break;
  }
  return "-y";
}

void validate_world(const World& world, const std::string& where) {
  Validator v{where, world, {}};
  std::map<std::string, std::string> names;  // name -> field of its first use
  auto name = [&](const std::string& n, const std::string& field) {
    if (n.empty()) {
      v.fail(field + ".name", "must not be empty");
    }
    const auto [it, inserted] = names.emplace(n, field);
    if (!inserted) {
      v.fail(field + ".name", "duplicate name '" + n + "' (also " + it->second + ")");
    }
  };
  for (std::size_t i = 0; i < world.walls.size(); ++i) {
    const std::string field = "walls[" + std::to_string(i) + "]";
    name(world.walls[i].name, field);
    v.shape(world.walls[i], field);
    if (world.walls[i].path) {
      v.fail(field + ".path", "walls do not move");
    }
    if (world.walls[i].type != WorldShape::Type::kBox) {
      v.fail(field + ".shape", "walls are boxes");
    }
  }
  for (std::size_t i = 0; i < world.obstacles.size(); ++i) {
    const std::string field = "obstacles[" + std::to_string(i) + "]";
    name(world.obstacles[i].name, field);
    v.shape(world.obstacles[i], field);
  }
  for (std::size_t i = 0; i < world.marks.size(); ++i) {
    const std::string field = "marks[" + std::to_string(i) + "]";
    name(world.marks[i].name, field);
    v.mark(world.marks[i], field);
  }
  for (std::size_t i = 0; i < world.surfaces.size(); ++i) {
    const std::string field = "surfaces[" + std::to_string(i) + "]";
    name(world.surfaces[i].name, field);
    v.surface(world.surfaces[i], field);
  }
}

namespace {

World parse_world_node(const YAML::Node& root, const Ctx& ctx) {
  World world;
  if (root.IsNull()) {
    return world;
  }
  if (!root.IsMap()) {
    ctx.fail("top level", "expected a map with floor, walls, obstacles, marks, surfaces");
  }
  for (const auto& kv : root) {
    const std::string key = key_text(ctx, kv.first, "top level");
    if (key != "floor" && key != "walls" && key != "obstacles" && key != "marks" &&
        key != "surfaces") {
      ctx.fail(key, "unknown key (expected floor, walls, obstacles, marks, surfaces)");
    }
  }
  if (const auto floor = root["floor"]) {
    if (floor.IsScalar()) {
      world.floor = boolean(ctx, floor, "floor");
    } else {
      only_keys(ctx, floor, "floor", {"enabled", "height", "friction"},
                "enabled, height, friction");
      if (floor["enabled"]) {
        world.floor = boolean(ctx, floor["enabled"], "floor.enabled");
      }
      if (floor["height"]) {
        world.floor_height = number(ctx, floor["height"], "floor.height");
      }
      if (floor["friction"]) {
        world.floor_friction = number(ctx, floor["friction"], "floor.friction");
      }
    }
  }
  auto each = [&](const char* key, auto&& parse_one) {
    const auto list = root[key];
    if (!list) {
      return;
    }
    if (!list.IsSequence()) {
      ctx.fail(key, "expected a list");
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      parse_one(list[i], std::string(key) + "[" + std::to_string(i) + "]");
    }
  };
  each("walls", [&](const YAML::Node& n, const std::string& f) {
    world.walls.push_back(shape(ctx, n, f, false));
  });
  each("obstacles", [&](const YAML::Node& n, const std::string& f) {
    world.obstacles.push_back(shape(ctx, n, f, true));
  });
  each("marks",
       [&](const YAML::Node& n, const std::string& f) { world.marks.push_back(mark(ctx, n, f)); });
  each("surfaces", [&](const YAML::Node& n, const std::string& f) {
    world.surfaces.push_back(surface(ctx, n, f));
  });
  return world;
}

}  // namespace

World parse_world_yaml(const std::string& text, const std::string& source) {
  const Ctx ctx{source};
  World world;
  try {
    world = parse_world_node(YAML::Load(text), ctx);
  } catch (const YAML::Exception& e) {
    // Not valid YAML, or a node of another kind than the reader checked for (the readers above
    // name the field where they can; this names the line for the rest).
    throw WorldError("world file '" + source + "': YAML error at line " +
                     std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  validate_world(world, "world file '" + source + "'");
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
