#include "planner/config.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <functional>
#include <map>
#include <sstream>

namespace concert::planner {
namespace {

std::string read_file(const std::filesystem::path& file, const char* what) {
  std::ifstream in(file);
  if (!in) throw PlannerError(std::string(what) + " file '" + file.string() + "' cannot be opened");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

YAML::Node parse(const std::string& yaml, const std::string& source) {
  try {
    return YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw PlannerError(source + ": YAML error: " + e.what());
  }
}

double number(const YAML::Node& n, const std::string& where) {
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    throw PlannerError(where + ": expected a number");
  }
}

Eigen::Vector3d vec3(const YAML::Node& n, const std::string& where) {
  if (!n.IsSequence() || n.size() != 3) throw PlannerError(where + ": expected a list of 3 numbers");
  return {number(n[0], where), number(n[1], where), number(n[2], where)};
}

}  // namespace

Params parse_params(const std::string& yaml, const std::string& source) {
  Params p;
  const YAML::Node root = parse(yaml, source);
  if (!root || root.IsNull()) return p;
  if (!root.IsMap()) throw PlannerError(source + ": expected a map of parameters");
  const std::map<std::string, double*> numbers = {
      {"camera_distance", &p.camera_distance},
      {"contact_force", &p.contact_force},
      {"torque_margin", &p.torque_margin},
      {"floor_height", &p.floor_height},
      {"base_height", &p.base_height},
      {"octomap_resolution", &p.octomap_resolution},
      {"environment_padding", &p.environment_padding},
      {"floor_clearance", &p.floor_clearance},
      {"base_range", &p.base_range},
      {"planning_time", &p.planning_time},
      {"warm_up_time", &p.warm_up_time},
      {"path_attempt_time", &p.path_attempt_time},
      {"check_resolution", &p.check_resolution},
      {"nspg_time", &p.nspg_time},
      {"nspg_tolerance", &p.nspg_tolerance},
      {"nspg_distance_weight", &p.nspg_distance_weight},
      {"nspg_singularity_weight", &p.nspg_singularity_weight},
      {"velocity_scale", &p.velocity_scale},
      {"joint_acceleration", &p.joint_acceleration},
      {"base_linear_velocity", &p.base_linear_velocity},
      {"base_linear_acceleration", &p.base_linear_acceleration},
      {"base_angular_velocity", &p.base_angular_velocity},
      {"base_angular_acceleration", &p.base_angular_acceleration},
      {"sample_period", &p.sample_period},
  };
  const std::map<std::string, int*> integers = {
      {"simplify_iterations", &p.simplify_iterations},
      {"sample_iterations", &p.sample_iterations},
      {"nspg_seeds", &p.nspg_seeds},
      {"nspg_screen", &p.nspg_screen},
      {"nspg_iterations", &p.nspg_iterations},
      {"nspg_enough", &p.nspg_enough},
      {"nspg_memory", &p.nspg_memory},
  };
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    const std::string where = source + ": " + key;
    if (const auto it = numbers.find(key); it != numbers.end()) {
      *it->second = number(kv.second, where);
    } else if (const auto jt = integers.find(key); jt != integers.end()) {
      const double v = number(kv.second, where);
      if (v < 0 || v != static_cast<int>(v)) throw PlannerError(where + ": expected a non-negative integer");
      *jt->second = static_cast<int>(v);
    } else if (key == "seed") {
      const double v = number(kv.second, where);
      if (v < 0) throw PlannerError(where + ": expected a non-negative integer");
      p.seed = static_cast<uint64_t>(v);
    } else {
      throw PlannerError(where + ": unknown parameter");
    }
  }
  for (const auto& [key, value] : numbers) {
    if (key != "base_height" && key != "floor_height" && !(*value >= 0.0)) {
      throw PlannerError(source + ": " + key + ": must be >= 0");
    }
  }
  if (!(p.planning_time > 0.0)) throw PlannerError(source + ": planning_time: must be > 0");
  if (!(p.check_resolution > 0.0)) throw PlannerError(source + ": check_resolution: must be > 0");
  if (!(p.octomap_resolution > 0.0)) throw PlannerError(source + ": octomap_resolution: must be > 0");
  return p;
}

Params load_params(const std::filesystem::path& file) { return parse_params(read_file(file, "params"), file.string()); }

World parse_world(const std::string& yaml, const std::string& source) {
  World w;
  const YAML::Node root = parse(yaml, source);
  if (!root || root.IsNull()) return w;
  if (!root.IsMap()) throw PlannerError(source + ": expected a map with walls/obstacles");
  auto read_list = [&](const std::string& key, bool allow_cylinders) {
    const YAML::Node list = root[key];
    if (!list) return;
    if (!list.IsSequence()) throw PlannerError(source + ": " + key + ": expected a list");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YAML::Node item = list[i];
      const std::string where = source + ": " + key + "[" + std::to_string(i) + "]";
      const std::string name = item["name"] ? item["name"].as<std::string>() : key + std::to_string(i);
      const std::string shape = item["shape"] ? item["shape"].as<std::string>() : "box";
      if (shape == "cylinder" && allow_cylinders) {
        if (!item["radius"] || !item["height"] || !item["position"]) {
          throw PlannerError(where + ": a cylinder needs radius, height and position");
        }
        w.cylinders.push_back({name, number(item["radius"], where + ".radius"), number(item["height"], where + ".height"),
                               vec3(item["position"], where + ".position")});
      } else if (shape == "box") {
        if (!item["size"] || !item["position"]) throw PlannerError(where + ": a box needs size and position");
        w.boxes.push_back({name, vec3(item["size"], where + ".size"), vec3(item["position"], where + ".position"),
                           item["yaw"] ? number(item["yaw"], where + ".yaw") : 0.0});
      } else {
        throw PlannerError(where + ".shape: unknown shape '" + shape + "' (box" + (allow_cylinders ? " or cylinder)" : ")"));
      }
    }
  };
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key != "walls" && key != "obstacles" && key != "floor") throw PlannerError(source + ": " + key + ": unknown key");
  }
  read_list("walls", false);
  read_list("obstacles", true);
  return w;
}

World load_world(const std::filesystem::path& file) { return parse_world(read_file(file, "world"), file.string()); }

}  // namespace concert::planner
