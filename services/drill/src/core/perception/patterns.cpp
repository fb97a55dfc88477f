// ArUco hole patterns: the table file (read with libs/config: errors name the file, the entry,
// the field and the line) and the holes of a pattern.
#include "drill/patterns.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "concert/common/text.hpp"
#include "concert/config/config.hpp"
#include "concert/world/aruco.hpp"
#include "drill/mission.hpp"

namespace concert::drill {

namespace {

/// The keys of the `patterns` map, in file order (config::Map reads keys it is given, it does
/// not list them).
std::vector<std::string> pattern_keys(const std::string& yaml) {
  std::vector<std::string> keys;
  const YAML::Node patterns = YAML::Load(yaml)["patterns"];
  if (patterns.IsMap()) {
    for (const auto& kv : patterns) {
      keys.push_back(kv.first.Scalar());
    }
  }
  return keys;
}

/// A marker id of a dictionary of `ids` markers, or fails naming the key.
int marker_id(config::Map& table, const std::string& key, const std::string& dictionary, int ids) {
  int id = -1;
  const bool digits =
      !key.empty() && key.size() < 9 &&
      std::all_of(key.begin(), key.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (digits) {
    id = std::stoi(key);
  }
  if (id < 0 || id >= ids) {
    table.fail(key,
               "expected a marker id of " + dictionary + " (0.." + std::to_string(ids - 1) + ")");
  }
  return id;
}

HolePattern pattern(config::Map& entry, int id) {
  for (const char* key : {"centre", "count", "spacing"}) {
    if (!entry.has(key)) {
      entry.fail(key,
                 "missing (each pattern gives centre [x, y] [m], direction [rad], count, "
                 "spacing [m])");
    }
  }
  HolePattern p;
  p.id = id;
  std::vector<double> centre;
  entry.numbers("centre", centre, 2);
  // An empty value (`centre:`) leaves the list as it was: empty.
  if (centre.size() != 2) entry.fail("centre", "expected [x, y] [m], got nothing");
  p.centre = {centre[0], centre[1]};
  entry.number("direction", p.direction);
  entry.integer("count", p.count, 1, 1000);
  entry.number("spacing", p.spacing, config::Range::non_negative());
  if (p.count > 1 && p.spacing <= 0.0) {
    entry.fail("spacing", "must be > 0 when count > 1 (got " + std::to_string(p.spacing) + ")");
  }
  return p;
}

}  // namespace

PatternTable::PatternTable(std::string source, std::string dictionary, double marker_size,
                           std::vector<HolePattern> patterns)
    : source_(std::move(source)),
      dictionary_(std::move(dictionary)),
      marker_size_(marker_size),
      patterns_(std::move(patterns)) {
  for (std::size_t i = 0; i < patterns_.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (patterns_[i].id == patterns_[j].id) {
        throw DrillError("pattern table " + source_ + ": patterns." +
                         std::to_string(patterns_[i].id) + ": marker id given twice");
      }
    }
  }
}

const HolePattern* PatternTable::find(int id) const {
  const auto it = std::find_if(patterns_.begin(), patterns_.end(),
                               [id](const HolePattern& p) { return p.id == id; });
  return it == patterns_.end() ? nullptr : &*it;
}

PatternTable parse_patterns(const std::string& yaml, const std::string& source) {
  try {
    config::Document doc = config::Document::parse(yaml, source);
    config::Map root = doc.root();
    std::string dictionary = "DICT_4X4_50";
    double marker_size = 0.1;
    root.choice("dictionary", dictionary, world::aruco_dictionary_names());
    root.number("marker_size", marker_size, config::Range::positive());
    if (!root.has("patterns")) {
      root.fail("patterns", "missing: a map from marker id to its hole pattern");
    }
    const int ids = world::aruco_dictionary_size(dictionary);
    config::Map table = root.section("patterns");
    std::vector<HolePattern> patterns;
    for (const std::string& key : pattern_keys(yaml)) {
      const int id = marker_id(table, key, dictionary, ids);
      config::Map entry = table.section(key);
      patterns.push_back(pattern(entry, id));
    }
    doc.finish();
    return PatternTable(source, dictionary, marker_size, std::move(patterns));
  } catch (const config::ConfigError& e) {
    throw DrillError(std::string("pattern table ") + e.what());
  }
}

PatternTable load_patterns(const std::filesystem::path& path) {
  std::string text;
  try {
    text = read_file(path, "pattern table");
  } catch (const std::runtime_error& e) {
    throw DrillError(e.what());
  }
  return parse_patterns(text, path.string());
}

std::vector<Eigen::Isometry3d> pattern_holes(const Eigen::Isometry3d& world_T_marker,
                                             const HolePattern& pattern) {
  const Eigen::Vector2d along(std::cos(pattern.direction), std::sin(pattern.direction));
  std::vector<Eigen::Isometry3d> holes;
  for (int i = 0; i < pattern.count; ++i) {
    const Eigen::Vector2d at =
        pattern.centre + (i - 0.5 * (pattern.count - 1)) * pattern.spacing * along;
    Eigen::Isometry3d marker_T_hole = Eigen::Isometry3d::Identity();
    marker_T_hole.translation() = Eigen::Vector3d(at.x(), at.y(), 0.0);
    holes.push_back(world_T_marker * marker_T_hole);
  }
  return holes;
}

}  // namespace concert::drill
