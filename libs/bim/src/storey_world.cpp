#include "concert/bim/storey_world.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "concert/world/geometry.hpp"

namespace concert::bim {

namespace {

struct Rect {
  int c0, c1, r0, r1;  // inclusive cell ranges
};

/// Cells merged into rectangles: runs along each row, then equal runs of consecutive rows.
std::vector<Rect> rectangles(std::vector<Eigen::Vector2i> cells) {
  std::sort(cells.begin(), cells.end(), [](const auto& a, const auto& b) {
    return a.y() < b.y() || (a.y() == b.y() && a.x() < b.x());
  });
  std::vector<Rect> runs;
  for (const auto& c : cells) {
    if (!runs.empty() && runs.back().r0 == c.y() && runs.back().c1 + 1 == c.x()) {
      runs.back().c1 = c.x();
    } else {
      runs.push_back({c.x(), c.x(), c.y(), c.y()});
    }
  }
  std::vector<Rect> out;
  std::map<std::pair<int, int>, std::size_t>
      open;  // (c0, c1) -> index in out of the rectangle ending on the last row
  int last_row = std::numeric_limits<int>::min();
  std::map<std::pair<int, int>, std::size_t> next;
  for (const auto& run : runs) {
    if (run.r0 != last_row) {
      open =
          run.r0 == last_row + 1 ? std::move(next) : std::map<std::pair<int, int>, std::size_t>{};
      next.clear();
      last_row = run.r0;
    }
    const auto key = std::make_pair(run.c0, run.c1);
    if (const auto it = open.find(key); it != open.end()) {
      out[it->second].r1 = run.r0;
      next[key] = it->second;
      open.erase(it);
    } else {
      out.push_back(run);
      next[key] = out.size() - 1;
    }
  }
  return out;
}

YAML::Node vec3(const Eigen::Vector3d& v) {
  YAML::Node n(YAML::NodeType::Sequence);
  n.SetStyle(YAML::EmitterStyle::Flow);
  for (int i = 0; i < 3; ++i) n.push_back(v[i]);
  return n;
}

}  // namespace

concert::world::World storey_world(const BimModel& model, const Storey& storey,
                                   const SliceParams& params, double max_height) {
  if (!(max_height > 0)) throw BimError("storey world: maximum box height must be > 0 m");
  const OccupancyGrid grid = storey_map(model, storey, params);
  concert::world::World w;
  w.floor = true;
  w.floor_height = 0.0;
  const double z_min = storey.elevation + params.band_min;
  const double z_max = storey.elevation + params.band_max;
  for (const auto& e : model.elements) {
    if (!is_obstacle(e.category)) continue;
    const auto cells = element_cells(e, grid, z_min, z_max);
    if (cells.empty()) continue;
    const double top = std::min(e.bounds.max().z() - storey.elevation, max_height);
    if (!(top > 0)) continue;
    int k = 0;
    for (const Rect& r : rectangles(cells)) {
      concert::world::WorldShape box;
      box.name = to_string(e.category) + "_" + e.global_id + "_" + std::to_string(k++);
      box.type = concert::world::WorldShape::Type::kBox;
      box.size = {(r.c1 - r.c0 + 1) * grid.resolution, (r.r1 - r.r0 + 1) * grid.resolution, top};
      const Eigen::Vector2d centre =
          grid.origin +
          grid.resolution * Eigen::Vector2d((r.c0 + r.c1 + 1) / 2.0, (r.r0 + r.r1 + 1) / 2.0);
      box.position = {centre.x(), centre.y(), top / 2};
      (e.category == Category::kWall ? w.walls : w.obstacles).push_back(std::move(box));
    }
  }
  return w;
}

WallSpot place_on_wall(const concert::world::World& world, const std::string& global_id, const Eigen::Vector3d& point,
                       const Eigen::Vector3d& normal, const Eigen::Vector2d& half, const std::string& what) {
  using concert::world::Face;
  const std::string prefix = to_string(Category::kWall) + "_" + global_id + "_";
  const Eigen::Vector3d n = normal.normalized();
  std::optional<WallSpot> best;
  double best_distance = std::numeric_limits<double>::infinity();
  bool any_box = false;
  for (const auto& box : world.walls) {
    if (box.name.rfind(prefix, 0) != 0) continue;
    any_box = true;
    for (const Face face : {Face::kPlusX, Face::kMinusX, Face::kPlusY, Face::kMinusY}) {
      const Eigen::Isometry3d frame = concert::world::face_frame(box, face);
      if (frame.linear().col(2).dot(n) < std::cos(0.3)) continue;
      const Eigen::Vector3d local = frame.inverse() * point;
      const Eigen::Vector2d size = concert::world::face_size(box, face);
      if (std::abs(local.x()) > size.x() / 2 - half.x() || std::abs(local.y()) > size.y() / 2 - half.y()) continue;
      // Within a few map cells of the face: the IFC's face and the boxes' are a cell apart at most.
      if (std::abs(local.z()) > 0.15 || std::abs(local.z()) >= best_distance) continue;
      best_distance = std::abs(local.z());
      Eigen::Isometry3d on_face = frame;
      on_face.translation() = frame * Eigen::Vector3d(local.x(), local.y(), 0.0);
      best = WallSpot{box.name, face, {local.x(), point.z()}, on_face};
    }
  }
  if (!best) {
    std::ostringstream where;
    where << "(" << point.x() << ", " << point.y() << ", " << point.z() << ")";
    throw BimError(what + ": wall " + global_id +
                   (any_box ? ": no face of its boxes looking that way holds it (within 0.15 m) at " + where.str()
                            : ": not in this storey's world (no box named " + prefix + "*)"));
  }
  return *best;
}

concert::world::Mark mark_on_wall(const concert::world::World& world, const std::string& global_id,
                                  const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                                  const std::string& name, double diameter) {
  const WallSpot spot = place_on_wall(world, global_id, point, normal, Eigen::Vector2d::Constant(diameter / 2),
                                      "mark '" + name + "'");
  concert::world::Mark m;
  m.name = name;
  m.type = concert::world::Mark::Type::kBlob;
  m.diameter = diameter;
  m.wall = spot.wall;
  m.face = spot.face;
  m.at = spot.at;
  return m;
}

std::string world_yaml(const concert::world::World& world) {
  YAML::Node root;
  root["floor"]["enabled"] = world.floor;
  root["floor"]["height"] = world.floor_height;
  root["floor"]["friction"] = world.floor_friction;
  auto shapes = [&](const std::vector<concert::world::WorldShape>& list, const char* key) {
    for (const auto& s : list) {
      if (s.type != concert::world::WorldShape::Type::kBox || s.path) {
        throw BimError("world_yaml: " + std::string(key) + " '" + s.name +
                       "': only static boxes are written");
      }
      YAML::Node n;
      n["name"] = s.name;
      n["size"] = vec3(s.size);
      n["position"] = vec3(s.position);
      n["yaw"] = s.yaw;
      n["friction"] = s.friction;
      root[key].push_back(n);
    }
  };
  shapes(world.walls, "walls");
  shapes(world.obstacles, "obstacles");
  for (const auto& m : world.marks) {
    YAML::Node n;
    n["name"] = m.name;
    n["wall"] = m.wall;
    n["face"] = concert::world::to_string(m.face);
    YAML::Node at(YAML::NodeType::Sequence);
    at.SetStyle(YAML::EmitterStyle::Flow);
    at.push_back(m.at.x());
    at.push_back(m.at.y());
    n["at"] = at;
    if (m.type == concert::world::Mark::Type::kBlob) {
      n["type"] = "blob";
      n["diameter"] = m.diameter;
      YAML::Node rgba(YAML::NodeType::Sequence);
      rgba.SetStyle(YAML::EmitterStyle::Flow);
      for (int i = 0; i < 4; ++i) rgba.push_back(m.rgba[i]);
      n["rgba"] = rgba;
    } else {
      n["type"] = "aruco";
      n["size"] = m.size;
      n["dictionary"] = m.dictionary;
      n["id"] = m.id;
      n["angle"] = m.angle;
    }
    root["marks"].push_back(n);
  }
  const auto pair = [](const Eigen::Vector2d& v) {
    YAML::Node n(YAML::NodeType::Sequence);
    n.SetStyle(YAML::EmitterStyle::Flow);
    n.push_back(v.x());
    n.push_back(v.y());
    return n;
  };
  for (const auto& surface : world.surfaces) {
    YAML::Node n;
    n["name"] = surface.name;
    n["wall"] = surface.wall;
    n["face"] = concert::world::to_string(surface.face);
    n["at"] = pair(surface.at);
    n["size"] = pair(surface.size);
    n["thickness"] = surface.thickness;
    n["resolution"] = surface.resolution;
    const auto features = [&](const std::vector<concert::world::SurfaceFeature>& list, const char* key,
                              const char* height) {
      for (const auto& f : list) {
        YAML::Node feature;
        feature.SetStyle(YAML::EmitterStyle::Flow);
        feature["at"] = pair(f.at);
        feature["radius"] = f.radius;
        feature[height] = f.height;
        n[key].push_back(feature);
      }
    };
    features(surface.bumps, "bumps", "height");
    features(surface.holes, "holes", "depth");
    root["surfaces"].push_back(n);
  }
  YAML::Emitter out;
  out.SetDoublePrecision(9);
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace concert::bim
