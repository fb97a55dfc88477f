#include "concert/bim/storey_world.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <map>

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

std::string world_yaml(const concert::world::World& world) {
  if (!world.marks.empty() || !world.surfaces.empty()) {
    throw BimError("world_yaml writes floors and boxes only, not marks or surfaces");
  }
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
  YAML::Emitter out;
  out.SetDoublePrecision(9);
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace concert::bim
