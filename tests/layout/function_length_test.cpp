// The services' DDS adapters stay thin: no function in services/*/src/dds/ or a main over 80
// lines, and the drill's adapter within 700 lines; nor in the files of the robot's 1 kHz loop
// (the LOOP lines of tests/layout/long_functions.txt); except what that list still names (each
// with the most lines it may have until it is split; issue #50). Function
// extents come from universal-ctags (its C++ parser gives each definition's first and last line;
// a hand-written brace counter would trip on lambdas, strings and macros).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kMaxFunctionLines = 80;
constexpr int kMaxAdapterLines = 700;

struct Allowed {
  std::map<std::string, int> functions;  // "FILE FUNCTION" -> most lines
  std::map<std::string, int> files;      // FILE -> most lines
  std::vector<std::string> loop_files;   // sources of the 1 kHz loop, checked like the adapters
};

Allowed read_allowed(const fs::path& list) {
  Allowed a;
  std::ifstream in(list);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    std::string first, file, function;
    row >> first;
    if (first == "FILE") {
      int lines = 0;
      row >> lines >> file;
      a.files[file] = lines;
    } else if (first == "LOOP") {
      row >> file;
      a.loop_files.push_back(file);
    } else {
      row >> file >> function;
      a.functions[file + " " + function] = std::stoi(first);
    }
  }
  return a;
}

/// The adapters' and mains' sources below `root`, relative to it.
std::vector<std::string> adapter_sources(const fs::path& root) {
  std::vector<std::string> files;
  for (const char* area : {"services", "tools"}) {
    if (!fs::is_directory(root / area)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root / area)) {
      if (!entry.is_regular_file() || entry.path().extension() != ".cpp") continue;
      const std::string rel = fs::relative(entry.path(), root).string();
      const bool adapter = rel.find("/src/dds/") != std::string::npos;
      const bool main = entry.path().filename() == "main.cpp" && entry.path().parent_path().filename() == "src";
      if (adapter || main) files.push_back(rel);
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

size_t line_count(const fs::path& file) {
  std::ifstream in(file);
  size_t n = 0;
  std::string line;
  while (std::getline(in, line)) ++n;
  return n;
}

/// What is wrong with the tree below `root` against `allowed` (empty: nothing).
std::vector<std::string> violations(const fs::path& root, const Allowed& allowed) {
  std::vector<std::string> out;
  auto files = adapter_sources(root);
  if (files.empty()) return {"no adapter or main sources below " + root.string()};
  for (const std::string& loop : allowed.loop_files) {
    if (fs::is_regular_file(root / loop)) {
      files.push_back(loop);
    } else {
      out.push_back(loop + " (a LOOP line of tests/layout/long_functions.txt) does not exist");
    }
  }
  std::vector<std::string> argv = {CONCERT_CTAGS, "--languages=C++", "--kinds-C++=f", "--fields=+ne",
                                   "--output-format=json", "-o", "-"};
  argv.insert(argv.end(), files.begin(), files.end());
  // Run from `root`, so that each tag's path is the file's path relative to the tree.
  std::vector<std::string> sh = {"/bin/sh", "-c", "cd \"$0\" && shift && exec \"$@\"", root.string(), "-"};
  sh.insert(sh.end(), argv.begin(), argv.end());
  const auto tags = concert::testing::run(sh, 120s);
  if (tags.code != 0) return {"ctags failed: " + tags.err};
  std::map<std::string, int> seen;  // listed functions found over the limit
  std::istringstream lines(tags.out);
  std::string line;
  while (std::getline(lines, line)) {
    const auto tag = nlohmann::json::parse(line, nullptr, false);
    if (tag.is_discarded() || !tag.contains("end") || !tag.contains("line")) continue;
    const std::string name = tag["name"];
    if (name.rfind("__anon", 0) == 0) continue;  // a lambda: it counts in its function
    const int length = tag["end"].get<int>() - tag["line"].get<int>() + 1;
    if (length <= kMaxFunctionLines) continue;
    const std::string key = tag["path"].get<std::string>() + " " + name;
    const std::string where = tag["path"].get<std::string>() + ":" + std::to_string(tag["line"].get<int>()) + " " + name;
    const auto listed = allowed.functions.find(key);
    if (listed == allowed.functions.end()) {
      const bool loop = std::find(allowed.loop_files.begin(), allowed.loop_files.end(),
                                  tag["path"].get<std::string>()) != allowed.loop_files.end();
      out.push_back(where + " has " + std::to_string(length) + " lines, over " + std::to_string(kMaxFunctionLines) +
                    (loop ? ": split it (a function of the 1 kHz loop)" : ": split it (the decisions belong in the service's core)"));
    } else if (length > listed->second) {
      out.push_back(where + " grew to " + std::to_string(length) + " lines (at most " +
                    std::to_string(listed->second) + " until it is split, tests/layout/long_functions.txt)");
    }
    seen[key] = length;
  }
  for (const auto& [key, most] : allowed.functions) {
    if (!seen.count(key)) {
      out.push_back(key + " is within " + std::to_string(kMaxFunctionLines) +
                    " lines now (or gone): remove it from tests/layout/long_functions.txt");
    }
  }
  for (const auto& file : files) {
    const bool drill = file == "services/drill/src/dds/drill_node.cpp";
    if (!drill) continue;
    const size_t n = line_count(root / file);
    const auto listed = allowed.files.find(file);
    const size_t most = listed != allowed.files.end() ? static_cast<size_t>(listed->second) : kMaxAdapterLines;
    if (n > most) {
      out.push_back(file + " has " + std::to_string(n) + " lines (at most " + std::to_string(most) + ")");
    } else if (listed != allowed.files.end() && n <= static_cast<size_t>(kMaxAdapterLines)) {
      out.push_back(file + " is within " + std::to_string(kMaxAdapterLines) +
                    " lines now: remove its FILE entry from tests/layout/long_functions.txt");
    }
  }
  return out;
}

TEST(FunctionLength, TheAdaptersAndMainsKeepTheirFunctionsShort) {
  const auto problems =
      violations(CONCERT_SOURCE_DIR, read_allowed(fs::path(CONCERT_SOURCE_DIR) / "tests/layout/long_functions.txt"));
  EXPECT_TRUE(problems.empty()) << ::testing::PrintToString(problems);
}

TEST(FunctionLength, ABadTreeFailsNamingTheFunction) {
  concert::testing::TempDir dir("layout-length");
  const fs::path adapter = fs::path(dir.path()) / "services/demo/src/dds";
  fs::create_directories(adapter);
  std::ofstream src(adapter / "demo_node.cpp");
  src << "namespace demo {\n\nint short_one() { return 1; }\n\nint long_one(int x) {\n";
  for (int i = 0; i < 85; ++i) src << "  x += " << i << ";  // a decision that belongs in the core\n";
  src << "  auto f = [&] {\n    return x;\n  };\n  return f();\n}\n\n}  // namespace demo\n";
  src.close();
  const auto problems = violations(dir.path(), Allowed{});
  ASSERT_EQ(problems.size(), 1u) << ::testing::PrintToString(problems);
  EXPECT_THAT(problems[0], ::testing::HasSubstr("services/demo/src/dds/demo_node.cpp:5 long_one has 91 lines"));
  // Listed with its length: allowed; listed with less: it grew.
  EXPECT_TRUE(violations(dir.path(), Allowed{{{"services/demo/src/dds/demo_node.cpp long_one", 91}}, {}}).empty());
  const auto grew = violations(dir.path(), Allowed{{{"services/demo/src/dds/demo_node.cpp long_one", 90}}, {}});
  ASSERT_EQ(grew.size(), 1u);
  EXPECT_THAT(grew[0], ::testing::HasSubstr("grew to 91 lines"));
  // A listed function that is short now must leave the list.
  const auto stale = violations(dir.path(), Allowed{{{"services/demo/src/dds/demo_node.cpp long_one", 91},
                                                      {"services/demo/src/dds/demo_node.cpp short_one", 90}},
                                                     {}});
  ASSERT_EQ(stale.size(), 1u);
  EXPECT_THAT(stale[0], ::testing::HasSubstr("short_one is within 80 lines now"));

  // A file of the 1 kHz loop outside the adapters is checked once a LOOP line names it.
  const fs::path core = fs::path(dir.path()) / "services/demo/src/core";
  fs::create_directories(core);
  fs::copy_file(adapter / "demo_node.cpp", core / "loop.cpp");
  Allowed loop{{{"services/demo/src/dds/demo_node.cpp long_one", 91}}, {}, {"services/demo/src/core/loop.cpp"}};
  const auto in_loop = violations(dir.path(), loop);
  ASSERT_EQ(in_loop.size(), 1u) << ::testing::PrintToString(in_loop);
  EXPECT_THAT(in_loop[0], ::testing::HasSubstr("services/demo/src/core/loop.cpp:5 long_one has 91 lines, over 80: "
                                               "split it (a function of the 1 kHz loop)"));
  loop.loop_files.push_back("services/demo/src/core/gone.cpp");
  EXPECT_THAT(violations(dir.path(), loop),
              ::testing::Contains(::testing::HasSubstr("services/demo/src/core/gone.cpp (a LOOP line")));
}

}  // namespace
