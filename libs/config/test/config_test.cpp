#include "concert/config/config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace concert::config {
namespace {

struct Params {
  double timestep = 0.001;
  int decimation = 10;
  unsigned seed = 1;
  bool real_time = true;
  std::optional<bool> floating = std::nullopt;
  std::string name = "robot";
  std::string order = "0312";
  std::chrono::milliseconds timeout{1000};
  std::vector<double> position{0.0, 0.0, 0.0};
  std::vector<std::string> services{"nav", "planner"};
  std::map<std::string, double> initial;
  std::map<std::string, std::string> packages;
};

/// A loader as a service writes one: sections, typed getters with ranges, then finish().
Params read(Document doc) {
  Params p;
  Map root = doc.root();
  root.string("name", p.name, false);
  root.choice("order", p.order, {"0312", "0123"});
  root.duration("timeout", p.timeout, Range::positive());
  root.strings("services", p.services, true);
  Map sim = root.section("sim");
  sim.number("timestep", p.timestep, Range::positive());
  sim.integer("decimation", p.decimation, 1, 1000);
  sim.integer("seed", p.seed);
  sim.boolean("real_time", p.real_time);
  sim.boolean_or_auto("floating", p.floating);
  sim.numbers("position", p.position, 3);
  sim.number_map("initial", p.initial);
  sim.string_map("packages", p.packages);
  doc.finish();
  return p;
}

Params read(const std::string& yaml) { return read(Document::parse(yaml, "robot.yaml")); }

std::string error_of(const std::string& yaml) {
  try {
    read(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Config, MissingKeysKeepTheirDefaults) {
  const Params p = read("");
  EXPECT_EQ(p.timestep, 0.001);
  EXPECT_EQ(p.timeout, std::chrono::milliseconds(1000));
  EXPECT_EQ(p.services, (std::vector<std::string>{"nav", "planner"}));
  EXPECT_EQ(read("sim: {}\n").decimation, 10);
}

TEST(Config, ReadWithHandsTheWholeDocumentToTheReader) {
  const auto reader = [](Document& doc) { return read(doc); };
  const Params p =
      Document::parse("name: arm\nsim: {decimation: 5}\n", "arm.yaml").read_with(reader);
  EXPECT_EQ(p.name, "arm");
  EXPECT_EQ(p.decimation, 5);
  try {
    (void)Document::parse("nmae: arm\n", "arm.yaml").read_with(reader);
    ADD_FAILURE() << "no error for an unknown key";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("arm.yaml: nmae: unknown key"), std::string::npos)
        << e.what();
  }
}

TEST(Config, EveryTypeIsRead) {
  const Params p = read(
      "name: arm\norder: '0123'\ntimeout: 0.25\nservices: drill\n"
      "sim:\n  timestep: 0.002\n  decimation: 5\n  seed: 7\n  real_time: no\n  floating: true\n"
      "  position: [1, 2.5, -3]\n  initial: {J1: 0.5}\n  packages: {res: /data}\n");
  EXPECT_EQ(p.name, "arm");
  EXPECT_EQ(p.order, "0123");
  EXPECT_EQ(p.timeout, std::chrono::milliseconds(250));
  EXPECT_EQ(p.services, std::vector<std::string>{"drill"});
  EXPECT_EQ(p.timestep, 0.002);
  EXPECT_EQ(p.decimation, 5);
  EXPECT_EQ(p.seed, 7u);
  EXPECT_FALSE(p.real_time);
  EXPECT_EQ(p.floating, std::optional<bool>(true));
  EXPECT_EQ(p.position, (std::vector<double>{1.0, 2.5, -3.0}));
  EXPECT_EQ(p.initial.at("J1"), 0.5);
  EXPECT_EQ(p.packages.at("res"), "/data");
  EXPECT_EQ(read("sim: {floating: auto}").floating, std::nullopt);
}

TEST(Config, WrongValuesNameFileKeyExpectationAndLine) {
  EXPECT_EQ(error_of("name: arm\nsim:\n  timestep: abc\n"),
            "robot.yaml: sim.timestep: expected a positive number, got 'abc' (line 3)");
  EXPECT_EQ(error_of("sim:\n  timestep: -1\n"),
            "robot.yaml: sim.timestep: expected a positive number, got '-1' (line 2)");
  EXPECT_EQ(error_of("sim:\n  decimation: 2.5\n"),
            "robot.yaml: sim.decimation: expected a whole number from 1 to 1000, got '2.5' (line "
            "2)");
  EXPECT_EQ(error_of("sim:\n  seed: -3\n"),
            "robot.yaml: sim.seed: expected a whole number >= 0, got '-3' (line 2)");
  EXPECT_EQ(error_of("sim:\n  real_time: maybe\n"),
            "robot.yaml: sim.real_time: expected true or false, got 'maybe' (line 2)");
  EXPECT_EQ(error_of("sim:\n  position: [1, 2]\n"),
            "robot.yaml: sim.position: expected a list of 3 numbers, got a list of 2 items (line "
            "2)");
  EXPECT_EQ(error_of("sim:\n  position: [1, x, 2]\n"),
            "robot.yaml: sim.position[1]: expected a number, got 'x'");
  EXPECT_EQ(error_of("order: 0321\n"),
            "robot.yaml: order: expected one of 0312, 0123, got '0321' (line 1)");
  EXPECT_EQ(error_of("name: ''\n"), "robot.yaml: name: expected a non-empty string (line 1)");
  EXPECT_EQ(error_of("timeout: 0.0001\n"),
            "robot.yaml: timeout: expected a duration of at least 0.001 s, got '0.0001' (line 1)");
  // Longer than the duration type holds: converting it would be undefined (fuzz_params).
  const std::string too_long = error_of("timeout: 1e300\n");
  EXPECT_EQ(too_long.rfind("robot.yaml: timeout: expected a duration shorter than ", 0), 0u) << too_long;
  EXPECT_NE(too_long.find(" s, got '1e300' (line 1)"), std::string::npos) << too_long;
  EXPECT_EQ(error_of("sim: 5\n"),
            "robot.yaml: sim: expected a map of parameters, got '5' (line 1)");
  EXPECT_EQ(error_of("- a\n- b\n"), "robot.yaml: expected a map of parameters, got a list");
  EXPECT_NE(error_of("sim: [1, \n").find("robot.yaml: not valid YAML"), std::string::npos);
}

TEST(Config, UnknownKeysAreRejectedWithTheKnownOnes) {
  EXPECT_EQ(error_of("sim:\n  timestep: 0.001\n  tmestep: 0.002\n"),
            "robot.yaml: sim.tmestep: unknown key (line 3); known keys of sim: decimation, "
            "floating, initial, packages, position, real_time, seed, timestep");
  EXPECT_EQ(error_of("nmae: arm\n"),
            "robot.yaml: nmae: unknown key (line 1); known keys: name, order, services, sim, "
            "timeout");
  EXPECT_EQ(error_of("name: a\nname: b\n"), "robot.yaml: name: given twice (line 2)");
}

/// A list of records, as a service's search order: each item a mapping of its own.
struct Attempt {
  bool reach = true;
  double further = 0.0;
  bool operator==(const Attempt&) const = default;
};

struct Search {
  std::vector<Attempt> attempts{{true, 0.0}, {false, 0.03}};
};

Search read_search(Document& doc) {
  Search s;
  doc.root().sequence("attempts", s.attempts, [](Map& item, Attempt& a) {
    item.boolean("reach", a.reach);
    item.number("further", a.further, Range::non_negative());
  });
  doc.finish();
  return s;
}

Search read_search(const std::string& yaml) {
  Document doc = Document::parse(yaml, "robot.yaml");
  return read_search(doc);
}

std::string search_error_of(const std::string& yaml) {
  try {
    read_search(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Config, SequenceReadsAListOfMaps) {
  // An item's missing key takes the fresh item's value (reach true), not the default list's at
  // its index (row 1: reach false).
  const Search s = read_search(
      "attempts:\n  - {reach: false, further: 0.1}\n  - {further: 0.2}\n  - reach: true\n"
      "    further: 0.3\n");
  EXPECT_EQ(s.attempts, (std::vector<Attempt>{{false, 0.1}, {true, 0.2}, {true, 0.3}}));
  EXPECT_EQ(read_search("").attempts, Search{}.attempts);
  EXPECT_EQ(read_search("attempts:\n").attempts, Search{}.attempts);
  EXPECT_TRUE(read_search("attempts: []\n").attempts.empty());

  // The untyped form: one Map per item, named key[i].
  Document doc =
      Document::parse("attempts:\n  - {reach: true}\n  - {further: 0.2}\n", "robot.yaml");
  std::vector<Map> items = doc.root().sequence("attempts");
  ASSERT_EQ(items.size(), 2u);
  EXPECT_EQ(items[1].path("further"), "attempts[1].further");
  EXPECT_TRUE(items[1].has("further"));
  EXPECT_FALSE(items[1].has("reach"));
  EXPECT_TRUE(Document::parse("", "robot.yaml").root().sequence("attempts").empty());
}

TEST(Config, SequenceItemErrorsNameTheItemKeyAndLine) {
  EXPECT_EQ(search_error_of("attempts:\n  - {reach: true}\n  - {reach: false, further: -1}\n"),
            "robot.yaml: attempts[1].further: expected a number >= 0, got '-1' (line 3)");
  EXPECT_EQ(search_error_of("attempts:\n  - further: 0.1\n  - reach: false\n    further: x\n"),
            "robot.yaml: attempts[1].further: expected a number >= 0, got 'x' (line 4)");
  // A rule of the service's about a key the item leaves out: the item's line.
  Document doc =
      Document::parse("attempts:\n  - {reach: true}\n  - {reach: false}\n", "robot.yaml");
  const std::vector<Map> items = doc.root().sequence("attempts");
  try {
    items[1].fail("further", "must be given when reach is false");
    ADD_FAILURE() << "fail() returned";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "robot.yaml: attempts[1].further: must be given when reach is false (line 3)");
  }
}

TEST(Config, SequenceItemUnknownKeysAreRejectedWithTheKnownOnes) {
  EXPECT_EQ(search_error_of("attempts:\n  - {reach: true}\n  - {reach: true, furthr: 0.1}\n"),
            "robot.yaml: attempts[1].furthr: unknown key (line 3); known keys of attempts[1]: "
            "further, reach");
  EXPECT_EQ(search_error_of("attempts:\n  - reach: true\n    reach: false\n"),
            "robot.yaml: attempts[0].reach: given twice (line 3)");
}

TEST(Config, SequenceOfSomethingElseIsRefused) {
  EXPECT_EQ(search_error_of("attempts: 5\n"),
            "robot.yaml: attempts: expected a list of maps, got '5' (line 1)");
  EXPECT_EQ(search_error_of("attempts: {reach: true}\n"),
            "robot.yaml: attempts: expected a list of maps, got a map (line 1)");
  EXPECT_EQ(search_error_of("attempts:\n  - {reach: true}\n  - 5\n"),
            "robot.yaml: attempts[1]: expected a map of parameters, got '5' (line 3)");
}

TEST(Config, SequenceDifferencesFromDefaultsGoItemByItem) {
  Document same = Document::parse(
      "attempts:\n  - {reach: true, further: 0.0}\n  - {reach: false, further: 0.03}\n",
      "robot.yaml");
  read_search(same);
  EXPECT_TRUE(same.differences_from_defaults().empty())
      << ::testing::PrintToString(same.differences_from_defaults());
  EXPECT_EQ(same.keys().size(), 5u);  // the list and two keys per item
  EXPECT_EQ(same.keys()[0].path, "attempts");
  EXPECT_EQ(same.keys()[4].path, "attempts[1].further");

  Document changed = Document::parse(
      "attempts:\n  - {reach: true, further: 0.0}\n  - {reach: false, further: 0.05}\n"
      "  - {reach: true}\n",
      "robot.yaml");
  read_search(changed);
  EXPECT_EQ(changed.differences_from_defaults(),
            (std::vector<std::string>{
                "robot.yaml: attempts: the file says 3 items, the default in code is 2 items",
                "robot.yaml: attempts[1].further: the file says 0.05, the default in code is 0.03",
                "robot.yaml: attempts[2].further: not listed (the default is 0)"}));

  Document absent = Document::parse("", "robot.yaml");
  read_search(absent);
  EXPECT_EQ(absent.differences_from_defaults(),
            std::vector<std::string>{"robot.yaml: attempts: not listed (the default is 2 items)"});
}

TEST(Config, LoadNamesTheFile) {
  const auto file = std::filesystem::temp_directory_path() / "concert_config_test.yaml";
  std::ofstream(file) << "sim:\n  timestep: 0.004\n";
  EXPECT_EQ(read(Document::load(file)).timestep, 0.004);
  std::filesystem::remove(file);
  try {
    Document::load(file);
    FAIL() << "no error for a missing file";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "parameters file '" + file.string() + "' cannot be opened");
  }
}

TEST(Config, DifferencesFromDefaultsNameMissingAndChangedKeys) {
  const std::string all =
      "name: robot\norder: '0312'\ntimeout: 1.0\nservices: [nav, planner]\n"
      "sim:\n  timestep: 0.001\n  decimation: 10\n  seed: 1\n  real_time: true\n"
      "  floating: auto\n  position: [0, 0, 0]\n  initial: {}\n  packages: {}\n";
  Document doc = Document::parse(all, "robot.yaml");
  read(doc);
  EXPECT_TRUE(doc.differences_from_defaults().empty())
      << ::testing::PrintToString(doc.differences_from_defaults());
  EXPECT_EQ(doc.keys().size(), 12u);

  Document changed = Document::parse("sim:\n  timestep: 0.002\n", "robot.yaml");
  read(changed);
  const auto diff = changed.differences_from_defaults();
  ASSERT_EQ(diff.size(), 12u);
  EXPECT_EQ(diff[0], "robot.yaml: name: not listed (the default is 'robot')");
  EXPECT_NE(std::find(diff.begin(), diff.end(),
                      "robot.yaml: sim.timestep: the file says 0.002, the default in code is "
                      "0.001"),
            diff.end());
}

TEST(Range, Describes) {
  EXPECT_EQ(Range::any().describe(), "a number");
  EXPECT_EQ(Range::positive().describe(), "a positive number");
  EXPECT_EQ(Range::non_negative().describe(), "a number >= 0");
  EXPECT_EQ(Range::at_least(1.5).describe(), "a number >= 1.5");
  EXPECT_EQ(Range::between(0, 1).describe(), "a number in [0, 1]");
  EXPECT_TRUE(Range::positive().contains(1e-9));
  EXPECT_FALSE(Range::positive().contains(0.0));
}

}  // namespace
}  // namespace concert::config
