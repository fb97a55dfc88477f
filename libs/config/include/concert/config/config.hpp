#pragma once
// Parameter files of the services: YAML read key by key into plain Params structs.
//
//   config::Document doc = config::Document::load("robot.yaml");
//   config::Map sim = doc.root().section("sim");
//   sim.number("timestep", params.sim.timestep, config::Range::positive());
//   doc.finish();  // keys of the file nobody asked for are errors
//
// A key missing from the file keeps the value it had (the default in code). Every error names
// the file, the key's dotted path and the line, e.g.
//   robot.yaml: sim.timestep: expected a positive number, got 'abc' (line 12)
// Every key a reader asks for is recorded, so a test can check that a shipped file lists every
// parameter with exactly its default (Document::differences_from_defaults).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace concert::config {

/// A parameter file that cannot be used; the message names the file, the key and the line.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The allowed values of a number: [min, max], or (min, max] when `min_open`.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;

  static Range any() { return {}; }
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true}; }
  static Range non_negative() { return at_least(0.0); }
  static Range at_least(double min) { return {min, std::numeric_limits<double>::infinity()}; }
  static Range between(double min, double max) { return {min, max}; }

  bool contains(double v) const;
  /// "a number", "a positive number", "a number >= 0", "a number in [0, 1]".
  std::string describe(std::string_view noun = "number") const;
};

namespace detail {
struct State;
}

/// One mapping of a parameter file (the root or a section), read key by key. Getters leave
/// `value` unchanged when the key is absent and throw ConfigError when it is present but wrong.
class Map {
 public:
  /// A real number in `range` (finite).
  void number(std::string_view key, double& value, Range range = {});
  /// A real number in `range`, or `auto` (stored as NaN: decided at run time).
  void number_or_auto(std::string_view key, double& value, Range range = {});
  /// A whole number in [min, max].
  template <class Int>
  requires std::is_integral_v<Int>
  void integer(std::string_view key, Int& value, long long min = std::numeric_limits<Int>::min(),
               long long max = static_cast<long long>(std::min<unsigned long long>(
                   std::numeric_limits<Int>::max(), std::numeric_limits<long long>::max()))) {
    long long v = static_cast<long long>(value);
    integer_value(key, v, min, max);
    value = static_cast<Int>(v);
  }
  /// true or false (YAML's yes/no/on/off too).
  void boolean(std::string_view key, bool& value);
  /// true, false or `auto` (nullopt: decided at run time).
  void boolean_or_auto(std::string_view key, std::optional<bool>& value);
  /// A string; with `allow_empty == false` an empty one is an error.
  void string(std::string_view key, std::string& value, bool allow_empty = true);
  /// One of `choices`.
  void choice(std::string_view key, std::string& value, const std::vector<std::string>& choices);
  /// A duration given in seconds in the file, each within `seconds`; a positive value shorter
  /// than one tick of Duration, or one longer than Duration holds (292 years in nanoseconds),
  /// is an error.
  template <class Duration>
  void duration(std::string_view key, Duration& value, Range seconds = Range::non_negative()) {
    double s = std::chrono::duration<double>(value).count();
    duration_value(key, s, seconds, std::chrono::duration<double>(Duration(1)).count(),
                   std::chrono::duration<double>(Duration::max()).count());
    if constexpr (std::chrono::treat_as_floating_point_v<typename Duration::rep>) {
      value = std::chrono::duration_cast<Duration>(std::chrono::duration<double>(s));
    } else {
      value = std::chrono::round<Duration>(std::chrono::duration<double>(s));
    }
  }
  /// A list of numbers, each in `each`; `size` > 0 requires exactly that many.
  void numbers(std::string_view key, std::vector<double>& value, size_t size = 0, Range each = {});
  /// A list of strings (none empty); with `scalar_as_list`, a single string is a list of one.
  void strings(std::string_view key, std::vector<std::string>& value, bool scalar_as_list = false);
  /// A map from names to numbers, each in `each`.
  void number_map(std::string_view key, std::map<std::string, double>& value, Range each = {});
  /// A map from names to strings.
  void string_map(std::string_view key, std::map<std::string, std::string>& value);
  /// The nested mapping under `key` (empty when absent). Its keys are checked by finish().
  Map section(std::string_view key);
  /// The list of mappings under `key`, one Map per item (none when absent). Item i's keys are
  /// named "key[i].field" in errors and records; an error of the item carries the line of the
  /// key it names, or the item's own line when the key is not in it; finish() refuses the
  /// item's unknown and repeated keys as a section's. A value that is not a list, or an item
  /// that is not a mapping, is an error. Records nothing for `key` itself (the form below does).
  std::vector<Map> sequence(std::string_view key);
  /// A list of records (a table such as a search order): when the file gives `key`, `value`
  /// becomes one T per item, each read by `read_item(Map&, T&)` starting from `fresh` (so an
  /// item's missing keys take fresh's values, whatever the default list holds). `key` is
  /// recorded with the list's length ("3 items"), and each item's keys as "key[i].field" with
  /// the default in code at the same index as the value before reading (fresh's past the
  /// default list's end), so differences_from_defaults() compares a list item by item. For
  /// that, `read_item` is called twice on an item that has a default at its index: it must
  /// only read. Returns the items' Maps for rules across keys (Map::fail).
  template <class T, class ReadItem>
  std::vector<Map> sequence(std::string_view key, std::vector<T>& value, ReadItem&& read_item,
                            const T& fresh = T{}) {
    std::optional<std::vector<Map>> items = sequence_items(key);
    record_length(key, value.size(), items ? items->size() : value.size());
    if (!items) return {};
    std::vector<T> out;
    out.reserve(items->size());
    for (size_t i = 0; i < items->size(); ++i) {
      Map& item = (*items)[i];
      T entry = fresh;
      if (i < value.size()) {
        T against = value[i];  // recorded: the default at this index, then the file's values
        read_item(item, against);
        const Quiet quiet(item);
        read_item(item, entry);
      } else {
        read_item(item, entry);
      }
      out.push_back(std::move(entry));
    }
    value = std::move(out);
    return std::move(*items);
  }

  /// True if the file sets `key` in this mapping.
  bool has(std::string_view key) const;
  /// "section.key" as errors name it.
  std::string path(std::string_view key) const;
  /// Throws ConfigError "FILE: PATH: WHAT (line N)" for this mapping's `key`.
  [[noreturn]] void fail(std::string_view key, std::string_view what) const;

 private:
  friend class Document;
  Map(std::shared_ptr<detail::State> state, size_t index)
      : state_(std::move(state)), index_(index) {}
  void integer_value(std::string_view key, long long& value, long long min, long long max);
  void duration_value(std::string_view key, double& seconds, Range range, double tick_s, double max_s);
  /// The items of the list under `key`; nullopt when it is absent or null.
  std::optional<std::vector<Map>> sequence_items(std::string_view key);
  /// Records `key` as a list of `before` items in code and `after` once read.
  void record_length(std::string_view key, size_t before, size_t after);
  /// While one lives, the getters of the whole document record nothing (a typed sequence's
  /// second reading of an item).
  class Quiet {
   public:
    explicit Quiet(const Map& map);
    ~Quiet();
    Quiet(const Quiet&) = delete;
    Quiet& operator=(const Quiet&) = delete;

   private:
    std::shared_ptr<detail::State> state_;
    bool was_;
  };

  std::shared_ptr<detail::State> state_;
  size_t index_;
};

/// A key a reader asked for, and what the file did with it.
struct KeyRecord {
  std::string path;    ///< dotted path, e.g. "sim.timestep"
  bool set = false;    ///< the file gives it
  std::string before;  ///< the value before reading (the default in code), as text
  std::string after;   ///< the value after reading, as text
};

/// One parameter file.
class Document {
 public:
  /// Reads `file`; throws ConfigError when it cannot be read or is not YAML.
  static Document load(const std::filesystem::path& file);
  /// Parses YAML `text`; `source` names it in errors (a file name).
  static Document parse(std::string_view text, std::string source);

  /// The top-level mapping (an empty file is an empty mapping).
  Map root();
  /// Reads this whole document with `reader` (a function of Document&, such as a service's
  /// read_params) and returns what it returns:
  ///   return config::Document::load(file).read_with(read_params);
  template <class Reader>
  auto read_with(Reader&& reader) {
    return std::forward<Reader>(reader)(*this);
  }
  /// Throws ConfigError for the first key of the file no reader asked for, naming it and the
  /// keys that are known at its place; also for a key given twice.
  void finish() const;

  const std::string& source() const;
  /// Every key read so far, in reading order.
  const std::vector<KeyRecord>& keys() const;
  /// For a file that documents the defaults: one line per known key the file leaves out and
  /// per key whose value differs from the default in code (the value it replaced). Empty when
  /// the file lists every parameter with its default.
  std::vector<std::string> differences_from_defaults() const;

 private:
  explicit Document(std::shared_ptr<detail::State> state) : state_(std::move(state)) {}
  std::shared_ptr<detail::State> state_;
};

}  // namespace concert::config
