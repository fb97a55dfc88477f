// Parameter files (libs/config: every service's --params YAML), through the safety service's
// reader and through a reader that asks for a key with every kind of getter the library has
// (numbers and ranges, `auto`, integers, booleans, strings, choices, durations, lists, maps,
// nested sections, lists of records), then finish() and the defaults report. Documented failure: ConfigError.
//
// Seeds: every parameter file the services ship (services/*/config/*.yaml) and one file that
// sets every key of the all-getters reader.
#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "concert/config/config.hpp"
#include "fuzz.hpp"
#include "safety/params.hpp"

namespace {

using namespace concert;

/// A record of a list (Map::sequence), as a table of search attempts is.
struct Row {
  double a = 0.0;
  bool b = false;
};

/// One key per getter of config::Map.
struct AllKinds {
  double number = 1.0;
  double positive = 1.0;
  double maybe_auto = 0.5;
  int32_t count = 3;
  uint64_t big = 7;
  bool flag = false;
  std::optional<bool> auto_flag;
  std::string name = "x";
  std::string mode = "a";
  std::chrono::milliseconds period{100};
  std::chrono::nanoseconds tick{1000};
  std::chrono::duration<double> seconds{0.5};
  std::vector<double> xyz{0, 0, 0};
  std::vector<std::string> names{"a"};
  std::map<std::string, double> gains;
  std::map<std::string, std::string> labels;
  double inner = 0.0;
  int64_t deep = 0;
  std::vector<Row> rows{{1.0, true}, {2.0, false}};
  double item_total = 0.0;
};

AllKinds read_all_kinds(config::Document& doc) {
  AllKinds p;
  config::Map root = doc.root();
  root.number("number", p.number);
  root.number("positive", p.positive, config::Range::positive());
  root.number_or_auto("maybe_auto", p.maybe_auto, config::Range::between(0.0, 1.0));
  root.integer("count", p.count, 0, 100);
  root.integer("big", p.big);
  root.boolean("flag", p.flag);
  root.boolean_or_auto("auto_flag", p.auto_flag);
  root.string("name", p.name, false);
  root.choice("mode", p.mode, {"a", "b", "c"});
  root.duration("period", p.period, config::Range{0.0, 3600.0, true});
  root.duration("tick", p.tick);
  root.duration("seconds", p.seconds, config::Range::at_least(-1.0));
  root.numbers("xyz", p.xyz, 3, config::Range::non_negative());
  root.strings("names", p.names, true);
  root.number_map("gains", p.gains, config::Range::non_negative());
  root.string_map("labels", p.labels);
  config::Map section = root.section("section");
  section.number("inner", p.inner);
  section.section("deeper").integer("deep", p.deep, -5, 5);
  root.sequence("rows", p.rows, [](config::Map& m, Row& r) {
    m.number("a", r.a, config::Range::non_negative());
    m.boolean("b", r.b);
  });
  for (config::Map& item : root.sequence("items")) {
    double v = 0.0;
    item.number("v", v);
    p.item_total += v;
  }
  (void)root.has("flag");
  doc.finish();
  return p;
}

constexpr const char* kEveryKey =
    R"(# Every key of the all-getters reader of tests/fuzz/fuzz_params.cpp.
number: -2.5
positive: 1e-3
maybe_auto: auto
count: 42
big: 9223372036854775807
flag: yes
auto_flag: auto
name: robot
mode: b
period: 0.25
tick: 1e-6
seconds: -0.5
xyz: [1, 2, 3]
names: single
gains: {kp: 500, kd: 10}
labels: {a: x, b: y}
section:
  inner: 7
  deeper: {deep: -5}
rows:
  - {a: 3, b: no}
  - {a: 0.5}
  - {b: yes}
items: [{v: 1}, {v: 2.5}]
)";

template <class Read>
void read(std::string_view text, Read reader) {
  try {
    config::Document doc = config::Document::parse(text, "params.yaml");
    (void)doc.read_with(reader);
    volatile size_t sink = doc.differences_from_defaults().size() + doc.keys().size();
    (void)sink;
  } catch (const config::ConfigError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = fuzz::text_of(data, size);
  read(text, safety::read_params);
  read(text, read_all_kinds);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  for (const auto& service : std::filesystem::directory_iterator(source_dir() / "services")) {
    if (std::filesystem::is_directory(service.path() / "config")) {
      seeds.add_files(service.path() / "config", ".yaml");
    }
  }
  seeds.add("every_key.yaml", kEveryKey);
  seeds.add_tokens(kYamlTokens);
  seeds.add_tokens({"auto"});
}
