#include "drill/mission.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "concert/common/source_text.hpp"
#include "concert/common/text.hpp"

namespace concert::drill {
namespace {

constexpr double kMaxDepth = 0.3;  // [m]

// Reads one mission document; every error names the mission, the field's path and why.
class Reader {
 public:
  explicit Reader(const std::string& source) : prefix_("mission '" + source + "'") {}

  [[noreturn]] void fail(const std::string& path, const std::string& why) const {
    throw DrillError(prefix_ + ": " + (path.empty() ? "" : path + ": ") + why);
  }

  static std::string child(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

  // A mapping whose keys are all in `keys`.
  void only_keys(const YAML::Node& node, const std::string& path,
                 const std::vector<std::string>& keys) const {
    if (!node.IsMap()) fail(path, "expected a map with " + join(keys));
    std::set<std::string> seen;
    for (const auto& entry : node) {
      if (!entry.first.IsScalar()) fail(path, "a key that is not a name");
      const auto key = entry.first.as<std::string>();
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
        fail(child(path, key), "unknown key (expected " + join(keys) + ")");
      }
      // yaml-cpp keeps the first of two equal keys: the second would be ignored silently.
      if (!seen.insert(key).second) fail(child(path, key), "given twice");
    }
  }

  std::string text(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar() || node.Scalar().empty()) fail(path, "expected a non-empty string");
    return node.Scalar();
  }

  double number(const YAML::Node& node, const std::string& path) const {
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value)) {
      fail(path, "expected a number" + got(node));
    }
    if (!std::isfinite(value)) fail(path, "expected a finite number" + got(node));
    return value;
  }

  int whole(const YAML::Node& node, const std::string& path, int min) const {
    int value = 0;
    if (!node.IsScalar() || !YAML::convert<int>::decode(node, value) || value < min) {
      fail(path, "expected a whole number >= " + std::to_string(min) + got(node));
    }
    return value;
  }

  // A list of N finite numbers (each >= 0 if `non_negative`); `what` says what it is.
  template <int N>
  Eigen::Matrix<double, N, 1> numbers(const YAML::Node& node, const std::string& path,
                                      const std::string& what, bool non_negative = false) const {
    if (!node.IsSequence() || node.size() != static_cast<std::size_t>(N)) {
      fail(path, "expected " + what);
    }
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) {
      const YAML::Node element = node[static_cast<std::size_t>(i)];
      const std::string item = path + "[" + std::to_string(i) + "]";
      v(i) = number(element, item);
      if (non_negative && v(i) < 0.0) fail(item, "expected a number >= 0" + got(element));
    }
    return v;
  }

  std::filesystem::path file(const YAML::Node& node, const std::string& path,
                             const std::filesystem::path& base_dir) const {
    std::filesystem::path p = text(node, path);
    if (p.is_relative() && !base_dir.empty()) p = (base_dir / p).lexically_normal();
    return p;
  }

 private:
  static std::string got(const YAML::Node& node) {
    return node.IsScalar() ? ", got '" + node.Scalar() + "'" : "";
  }

  std::string prefix_;
};

AreaSpec read_area(const Reader& r, const YAML::Node& node, std::size_t index) {
  const std::string path = "areas[" + std::to_string(index) + "]";
  r.only_keys(node, path, {"name", "marks", "wall", "at", "face", "point", "pixel", "expected"});
  AreaSpec area;
  area.name =
      node["name"] ? r.text(node["name"], path + ".name") : "area " + std::to_string(index + 1);
  if (const auto marks = node["marks"]) {
    const std::string kind = r.text(marks, path + ".marks");
    if (kind != "blobs" && kind != "aruco") {
      r.fail(path + ".marks", "expected blobs or aruco, got '" + kind + "'");
    }
    area.marks = kind == "blobs" ? MarkKind::kBlobs : MarkKind::kAruco;
  }

  std::vector<std::string> has;
  for (const char* key : {"wall", "point", "pixel"}) {
    if (node[key]) has.emplace_back(key);
  }
  if (has.size() != 1) {
    r.fail(path, "needs exactly one of wall, point, pixel (has " +
                     (has.empty() ? std::string("none") : join(has, " and ")) + ")");
  }
  if (const auto wall = node["wall"]) {
    area.wall = r.text(wall, path + ".wall");
    if (!node["at"]) {
      r.fail(path + ".at",
             "missing: a wall area needs its centre [s, h] on the wall (m along the wall from its "
             "start, m above the storey)");
    }
  }
  if (const auto at = node["at"]) {
    if (area.wall.empty()) r.fail(path + ".at", "goes with wall (the centre of a wall area)");
    area.at = r.numbers<2>(at, path + ".at", "[s, h]: m along the wall, m above the storey", true);
  }
  if (const auto face = node["face"]) {
    if (area.wall.empty()) r.fail(path + ".face", "goes with wall (the face of a wall area)");
    area.face = r.text(face, path + ".face");
    if (area.face != "auto" && area.face != "left" && area.face != "right") {
      r.fail(path + ".face", "expected auto, left or right, got '" + area.face + "'");
    }
  }
  if (const auto point = node["point"]) {
    area.point = r.numbers<3>(point, path + ".point", "[x, y, z] in the map frame [m]");
  }
  if (const auto pixel = node["pixel"]) {
    area.pixel = r.numbers<2>(pixel, path + ".pixel", "[u, v] in the drill camera's image", true);
  }
  if (const auto expected = node["expected"]) {
    area.expected = r.whole(expected, path + ".expected", 0);
  }
  return area;
}

}  // namespace

namespace {

Mission parse_mission_yaml(const std::string& yaml, const std::string& source,
                           const std::filesystem::path& base_dir) {
  const Reader r(source);
  const YAML::Node root = parse_yaml<DrillError>(yaml, "mission '" + source + "'");
  if (!root || root.IsNull()) r.fail("areas", "missing: a mission needs at least one area");
  r.only_keys(root, "", {"name", "ifc", "storey", "patterns", "depth", "areas"});

  Mission mission;
  mission.name =
      root["name"] ? r.text(root["name"], "name") : std::filesystem::path(source).stem().string();
  if (root["ifc"]) mission.ifc = r.file(root["ifc"], "ifc", base_dir);
  if (root["storey"]) mission.storey = r.text(root["storey"], "storey");
  if (root["patterns"]) mission.patterns = r.file(root["patterns"], "patterns", base_dir);
  if (root["depth"]) {
    mission.depth = r.number(root["depth"], "depth");
    if (mission.depth <= 0.0 || mission.depth > kMaxDepth) {
      r.fail("depth", "expected a depth in (0, 0.3] m, got " + root["depth"].Scalar());
    }
  }

  const YAML::Node areas = root["areas"];
  if (!areas) r.fail("areas", "missing: a mission needs at least one area");
  if (!areas.IsSequence() || areas.size() == 0) {
    r.fail("areas", "expected a list of at least one area");
  }
  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < areas.size(); ++i) {
    AreaSpec area = read_area(r, areas[i], i);
    const std::string path = "areas[" + std::to_string(i) + "]";
    if (const auto [it, added] = names.emplace(area.name, i); !added) {
      r.fail(path + ".name",
             "'" + area.name + "' is also the name of areas[" + std::to_string(it->second) + "]");
    }
    if (!area.wall.empty() && mission.ifc.empty()) {
      r.fail(path + ".wall", "a wall area needs the building model: set ifc at the top level");
    }
    mission.areas.push_back(std::move(area));
  }
  return mission;
}

}  // namespace

Mission parse_mission(const std::string& yaml, const std::string& source,
                      const std::filesystem::path& base_dir) {
  try {
    return parse_mission_yaml(yaml, source, base_dir);
  } catch (const YAML::Exception& e) {
    // What the checks above do not name (a node of an unexpected kind deep inside).
    throw DrillError("mission '" + source + "': " + e.what());
  }
}

Mission load_mission(const std::filesystem::path& file) {
  return parse_mission(read_text<DrillError>(file, "the mission file"), file.string(),
                       file.parent_path());
}

}  // namespace concert::drill
