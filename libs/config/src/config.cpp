#include "concert/config/config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <charconv>
#include <set>
#include <utility>

#include "concert/common/text.hpp"

namespace concert::config {

namespace detail {

/// One mapping being read: its node (null when absent), its dotted path and the keys asked;
/// `item`: a list's item (Map::sequence), whose errors fall back to its own line.
struct MapState {
  YAML::Node node;
  std::string path;
  std::vector<std::string> known;
  bool item = false;
};

struct State {
  std::string source;
  std::vector<MapState> maps;  // index 0: the root
  std::vector<KeyRecord> keys;
  bool recording = true;  // false while a typed sequence reads an item the second time
};

}  // namespace detail

namespace {

std::string line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? "" : " (line " + std::to_string(mark.line + 1) + ")";
}

/// What a node holds, for "got ..." in errors.
std::string got(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "nothing";
}

std::string text_of(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string text_of(const std::vector<double>& v) {
  std::vector<std::string> items;
  for (double x : v) items.push_back(text_of(x));
  return "[" + join(items) + "]";
}

std::string text_of(const std::vector<std::string>& v) { return "[" + join(v) + "]"; }

std::string text_of(const std::map<std::string, double>& m) {
  std::vector<std::string> items;
  for (const auto& [k, v] : m) items.push_back(k + ": " + text_of(v));
  return "{" + join(items) + "}";
}

std::string text_of(const std::map<std::string, std::string>& m) {
  std::vector<std::string> items;
  for (const auto& [k, v] : m) items.push_back(k + ": " + v);
  return "{" + join(items) + "}";
}

}  // namespace

bool Range::contains(double v) const { return (min_open ? v > min : v >= min) && v <= max; }

std::string Range::describe(std::string_view noun) const {
  const std::string n(noun);
  const bool low = std::isfinite(min);
  const bool high = std::isfinite(max);
  if (!low && !high) return "a " + n;
  if (low && !high) {
    if (min == 0.0) return min_open ? "a positive " + n : "a " + n + " >= 0";
    return "a " + n + (min_open ? " > " : " >= ") + text_of(min);
  }
  if (!low) return "a " + n + " <= " + text_of(max);
  return "a " + n + " in " + (min_open ? "(" : "[") + text_of(min) + ", " + text_of(max) + "]";
}

// ---- Map ----------------------------------------------------------------------------------

std::string Map::path(std::string_view key) const {
  const std::string& base = state_->maps[index_].path;
  return base.empty() ? std::string(key) : base + "." + std::string(key);
}

bool Map::has(std::string_view key) const {
  const YAML::Node& node = std::as_const(state_->maps[index_].node);
  return node.IsMap() && node[std::string(key)];
}

void Map::fail(std::string_view key, std::string_view what) const {
  const detail::MapState& map = state_->maps[index_];
  const YAML::Node& node = std::as_const(map.node);
  std::string line;
  if (node.IsMap()) {
    if (const YAML::Node value = node[std::string(key)]) line = line_of(value);
  }
  // A list item's rule about a key it leaves out: the item's line.
  if (line.empty() && map.item && node) line = line_of(node);
  throw ConfigError(state_->source + ": " + path(key) + ": " + std::string(what) + line);
}

namespace {

/// The value node of `key` (registering the key as known), or a null node when absent.
YAML::Node lookup(detail::State& state, size_t index, std::string_view key) {
  detail::MapState& map = state.maps[index];
  if (std::find(map.known.begin(), map.known.end(), key) == map.known.end()) {
    map.known.emplace_back(key);
  }
  const YAML::Node& node = map.node;
  if (!node.IsMap()) return YAML::Node();
  const YAML::Node value = node[std::string(key)];
  return value ? value : YAML::Node();
}

/// The scalar `node` as T, or nullopt when it is not a scalar of that type.
template <class T>
std::optional<T> scalar_as(const YAML::Node& node) {
  if (!node.IsScalar()) return std::nullopt;
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    return std::nullopt;
  }
}

double scalar_number(const Map& map, std::string_view key, const YAML::Node& node, Range range,
                     std::string_view noun = "number", std::string_view alternative = "") {
  const std::optional<double> v = scalar_as<double>(node);
  if (!v || !std::isfinite(*v) || !range.contains(*v)) {
    map.fail(key,
             "expected " + range.describe(noun) + std::string(alternative) + ", got " + got(node));
  }
  return *v;
}

void record(detail::State& state, std::string path, const YAML::Node& node, std::string before,
            std::string after) {
  if (!state.recording) return;
  state.keys.push_back(
      {std::move(path), node && !node.IsNull(), std::move(before), std::move(after)});
}

}  // namespace

void Map::number(std::string_view key, double& value, Range range) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = text_of(value);
  if (node && !node.IsNull()) value = scalar_number(*this, key, node, range);
  record(*state_, path(key), node, before, text_of(value));
}

void Map::number_or_auto(std::string_view key, double& value, Range range) {
  const YAML::Node node = lookup(*state_, index_, key);
  auto text = [](double v) { return std::isnan(v) ? std::string("auto") : text_of(v); };
  const std::string before = text(value);
  if (node && !node.IsNull()) {
    if (node.IsScalar() && node.Scalar() == "auto") {
      value = std::numeric_limits<double>::quiet_NaN();
    } else {
      value = scalar_number(*this, key, node, range, "number", " or auto");
    }
  }
  record(*state_, path(key), node, before, text(value));
}

void Map::integer_value(std::string_view key, long long& value, long long min, long long max) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = std::to_string(value);
  if (node && !node.IsNull()) {
    const std::optional<long long> v = scalar_as<long long>(node);
    if (!v || *v < min || *v > max) {
      // Bounds beyond 32 bits are the type's, not the parameter's: not worth printing.
      constexpr long long kLarge = 2'147'483'647;
      std::string what = "a whole number";
      if (min == 0 && max >= kLarge) {
        what += " >= 0";
      } else if (min > -kLarge - 1 || max < kLarge) {
        what += " from " + std::to_string(min) + " to " + std::to_string(max);
      }
      fail(key, "expected " + what + ", got " + got(node));
    }
    value = *v;
  }
  record(*state_, path(key), node, before, std::to_string(value));
}

void Map::duration_value(std::string_view key, double& seconds, Range range, double tick_s, double max_s) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = text_of(seconds);
  if (node && !node.IsNull()) {
    const double v = scalar_number(*this, key, node, range, "duration in seconds");
    if (v > 0.0 && v < tick_s / 2) {
      fail(key, "expected a duration of at least " + text_of(tick_s) + " s, got " + got(node));
    }
    // Converting a longer one to an integer count of ticks is undefined (e.g. 1e56 s into
    // nanoseconds: tests/fuzz/regressions/fuzz_params). max_s is the duration type's largest,
    // rounded up as a double.
    if (std::abs(v) >= max_s) {
      fail(key, "expected a duration shorter than " + text_of(max_s) + " s, got " + got(node));
    }
    seconds = v;
  }
  record(*state_, path(key), node, before, text_of(seconds));
}

void Map::boolean(std::string_view key, bool& value) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = value ? "true" : "false";
  if (node && !node.IsNull()) {
    const std::optional<bool> v = scalar_as<bool>(node);
    if (!v) fail(key, "expected true or false, got " + got(node));
    value = *v;
  }
  record(*state_, path(key), node, before, value ? "true" : "false");
}

void Map::boolean_or_auto(std::string_view key, std::optional<bool>& value) {
  const YAML::Node node = lookup(*state_, index_, key);
  auto text = [](const std::optional<bool>& v) { return v ? (*v ? "true" : "false") : "auto"; };
  const std::string before = text(value);
  if (node && !node.IsNull()) {
    if (node.IsScalar() && node.Scalar() == "auto") {
      value.reset();
    } else {
      const std::optional<bool> v = scalar_as<bool>(node);
      if (!v) fail(key, "expected true, false or auto, got " + got(node));
      value = *v;
    }
  }
  record(*state_, path(key), node, before, text(value));
}

void Map::string(std::string_view key, std::string& value, bool allow_empty) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = "'" + value + "'";
  if (node && !node.IsNull()) {
    if (!node.IsScalar()) fail(key, "expected a string, got " + got(node));
    if (!allow_empty && node.Scalar().empty()) fail(key, "expected a non-empty string");
    value = node.Scalar();
  }
  record(*state_, path(key), node, before, "'" + value + "'");
}

void Map::choice(std::string_view key, std::string& value,
                 const std::vector<std::string>& choices) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = "'" + value + "'";
  if (node && !node.IsNull()) {
    if (!node.IsScalar() ||
        std::find(choices.begin(), choices.end(), node.Scalar()) == choices.end()) {
      fail(key, "expected one of " + join(choices) + ", got " + got(node));
    }
    value = node.Scalar();
  }
  record(*state_, path(key), node, before, "'" + value + "'");
}

void Map::numbers(std::string_view key, std::vector<double>& value, size_t size, Range each) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = text_of(value);
  if (node && !node.IsNull()) {
    const std::string what =
        size > 0 ? "a list of " + std::to_string(size) + " numbers" : "a list of numbers";
    if (!node.IsSequence() || (size > 0 && node.size() != size)) {
      fail(key, "expected " + what + ", got " +
                    (node.IsSequence() ? "a list of " + std::to_string(node.size()) + " items"
                                       : got(node)));
    }
    std::vector<double> out;
    for (size_t i = 0; i < node.size(); ++i) {
      out.push_back(
          scalar_number(*this, std::string(key) + "[" + std::to_string(i) + "]", node[i], each));
    }
    value = std::move(out);
  }
  record(*state_, path(key), node, before, text_of(value));
}

void Map::strings(std::string_view key, std::vector<std::string>& value, bool scalar_as_list) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = text_of(value);
  if (node && !node.IsNull()) {
    std::vector<std::string> out;
    if (scalar_as_list && node.IsScalar() && !node.Scalar().empty()) {
      out.push_back(node.Scalar());
    } else if (node.IsSequence()) {
      for (size_t i = 0; i < node.size(); ++i) {
        if (!node[i].IsScalar() || node[i].Scalar().empty()) {
          fail(key,
               "item " + std::to_string(i) + ": expected a non-empty string, got " + got(node[i]));
        }
        out.push_back(node[i].Scalar());
      }
    } else {
      fail(key, std::string("expected a list of strings") +
                    (scalar_as_list ? " or one string" : "") + ", got " + got(node));
    }
    value = std::move(out);
  }
  record(*state_, path(key), node, before, text_of(value));
}

void Map::number_map(std::string_view key, std::map<std::string, double>& value, Range each) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = text_of(value);
  if (node && !node.IsNull()) {
    if (!node.IsMap()) fail(key, "expected a map of names to numbers, got " + got(node));
    std::map<std::string, double> out;
    for (const auto& kv : node) {
      const std::string name = kv.first.Scalar();
      out[name] = scalar_number(*this, std::string(key) + "." + name, kv.second, each);
    }
    value = std::move(out);
  }
  record(*state_, path(key), node, before, text_of(value));
}

void Map::string_map(std::string_view key, std::map<std::string, std::string>& value) {
  const YAML::Node node = lookup(*state_, index_, key);
  const std::string before = text_of(value);
  if (node && !node.IsNull()) {
    if (!node.IsMap()) fail(key, "expected a map of names to strings, got " + got(node));
    std::map<std::string, std::string> out;
    for (const auto& kv : node) {
      if (!kv.second.IsScalar()) {
        fail(key, kv.first.Scalar() + ": expected a string, got " + got(kv.second));
      }
      out[kv.first.Scalar()] = kv.second.Scalar();
    }
    value = std::move(out);
  }
  record(*state_, path(key), node, before, text_of(value));
}

Map Map::section(std::string_view key) {
  const YAML::Node node = lookup(*state_, index_, key);
  if (node && !node.IsNull() && !node.IsMap()) {
    fail(key, "expected a map of parameters, got " + got(node));
  }
  state_->maps.push_back({node, path(key), {}});
  return Map(state_, state_->maps.size() - 1);
}

std::optional<std::vector<Map>> Map::sequence_items(std::string_view key) {
  const YAML::Node node = lookup(*state_, index_, key);
  if (!node || node.IsNull()) return std::nullopt;
  if (!node.IsSequence()) fail(key, "expected a list of maps, got " + got(node));
  std::vector<Map> items;
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node item = node[i];
    const std::string item_path = path(key) + "[" + std::to_string(i) + "]";
    if (!item.IsMap()) {
      throw ConfigError(state_->source + ": " + item_path + ": expected a map of parameters, got " +
                        got(item) + line_of(item));
    }
    state_->maps.push_back({item, item_path, {}, true});
    items.push_back(Map(state_, state_->maps.size() - 1));
  }
  return items;
}

std::vector<Map> Map::sequence(std::string_view key) {
  std::optional<std::vector<Map>> items = sequence_items(key);
  return items ? std::move(*items) : std::vector<Map>{};
}

void Map::record_length(std::string_view key, size_t before, size_t after) {
  const YAML::Node node = lookup(*state_, index_, key);
  const auto text = [](size_t n) { return std::to_string(n) + (n == 1 ? " item" : " items"); };
  record(*state_, path(key), node, text(before), text(after));
}

Map::Quiet::Quiet(const Map& map) : state_(map.state_), was_(map.state_->recording) {
  state_->recording = false;
}

Map::Quiet::~Quiet() { state_->recording = was_; }

// ---- Document -----------------------------------------------------------------------------

Document Document::parse(std::string_view text, std::string source) {
  auto state = std::make_shared<detail::State>();
  state->source = std::move(source);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw ConfigError(state->source + ": not valid YAML: " + e.msg + " (line " +
                      std::to_string(e.mark.line + 1) + ")");
  }
  if (root && !root.IsNull() && !root.IsMap()) {
    throw ConfigError(state->source + ": expected a map of parameters, got " + got(root));
  }
  state->maps.push_back({root, "", {}});
  return Document(std::move(state));
}

Document Document::load(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_file(file, "parameters");
  } catch (const std::runtime_error& e) {
    throw ConfigError(e.what());
  }
  return parse(text, file.string());
}

Map Document::root() { return Map(state_, 0); }

void Document::finish() const {
  for (const detail::MapState& map : state_->maps) {
    if (!map.node.IsMap()) continue;
    std::set<std::string> seen;
    for (const auto& kv : map.node) {
      const std::string key = kv.first.Scalar();
      const std::string path = map.path.empty() ? key : map.path + "." + key;
      if (!seen.insert(key).second) {
        throw ConfigError(state_->source + ": " + path + ": given twice" + line_of(kv.first));
      }
      if (std::find(map.known.begin(), map.known.end(), key) == map.known.end()) {
        std::vector<std::string> known = map.known;
        std::sort(known.begin(), known.end());
        throw ConfigError(state_->source + ": " + path + ": unknown key" + line_of(kv.first) +
                          "; known keys" + (map.path.empty() ? "" : " of " + map.path) + ": " +
                          join(known));
      }
    }
  }
}

const std::string& Document::source() const { return state_->source; }

const std::vector<KeyRecord>& Document::keys() const { return state_->keys; }

std::vector<std::string> Document::differences_from_defaults() const {
  std::vector<std::string> out;
  for (const KeyRecord& k : state_->keys) {
    if (!k.set) {
      out.push_back(state_->source + ": " + k.path + ": not listed (the default is " + k.before +
                    ")");
    } else if (k.before != k.after) {
      out.push_back(state_->source + ": " + k.path + ": the file says " + k.after +
                    ", the default in code is " + k.before);
    }
  }
  return out;
}

}  // namespace concert::config
