// The `concert` command line (libs/cli on CLI11, every verb the tool and the built services
// register: tools/concert register_all), parsed as the tool parses argv. Properties: parsing
// never throws and ends in exit code 0 (a verb chosen, or help shown) or 2 (a wrong command
// line, with a message); `concert help VERB...`, which runs without DDS, runs too.
//
// Input: the arguments after the program name, separated by NUL bytes (argv cannot hold NUL).
// Seeds: every command line of the repository's README files, and for every verb its words,
// with --help, and with each of its options given a value.
#include <fstream>
#include <sstream>

#include "concert/cli/cli.hpp"
#include "fuzz.hpp"
#include "verbs.hpp"

namespace {

using namespace concert;

int parse(const std::vector<std::string>& args, bool run) {
  std::ostringstream out, err;
  cli::Cli concert("concert", "the CONCERT stack's command line", out, err);
  tool::register_all(concert);
  const int code = run ? concert.run(args) : concert.parse_only(args);
  CONCERT_FUZZ_CHECK(code == 0 || code == 2 || (run && code == 1),
                     "exit code " + std::to_string(code) + " from parsing: " + err.str());
  CONCERT_FUZZ_CHECK(code == 0 || !err.str().empty(), "a refused command line without a message");
  return code;
}

std::string nul_joined(const std::vector<std::string>& args) {
  std::string s;
  for (size_t i = 0; i < args.size(); ++i) s += (i ? std::string(1, '\0') : "") + args[i];
  return s;
}

/// The words after `concert` on a README line: up to a comment, a backtick or the end; quotes
/// group words as the shell does; a trailing backslash continues on the next line (dropped).
std::vector<std::string> words_after_concert(const std::string& line) {
  static const std::string kTool = "concert ";
  size_t at = std::string::npos;
  for (size_t p = line.find(kTool); p != std::string::npos; p = line.find(kTool, p + 1)) {
    if (p == 0 || line[p - 1] == ' ' || line[p - 1] == '/') {
      at = p + kTool.size();
      break;
    }
  }
  std::vector<std::string> words;
  if (at == std::string::npos) return words;
  std::string word;
  bool in_word = false;
  char quote = 0;
  for (size_t i = at; i < line.size(); ++i) {
    const char c = line[i];
    if (quote != 0) {
      if (c == quote) {
        quote = 0;
      } else {
        word += c;
      }
      continue;
    }
    if (c == '#' || c == '`' || c == '\\') break;
    if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<std::string> args;
  if (size > 0) {
    for (std::string_view a : fuzz::split(fuzz::text_of(data, size), '\0', 256))
      args.emplace_back(a);
  }
  const int code = parse(args, false);
  if (code == 0 && !args.empty() && args.front() == "help") parse(args, true);
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  size_t n = 0;
  const auto add = [&](const std::vector<std::string>& args) {
    seeds.add("args_" + std::to_string(n++), nul_joined(args));
  };
  // The command lines of the documentation.
  std::vector<std::filesystem::path> readmes;
  for (auto it = std::filesystem::recursive_directory_iterator(source_dir());
       it != std::filesystem::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory() &&
        (name.rfind("build", 0) == 0 || name == "node_modules" || name.front() == '.')) {
      it.disable_recursion_pending();
    } else if (it->is_regular_file() && name == "README.md") {
      readmes.push_back(it->path());
    }
  }
  std::sort(readmes.begin(), readmes.end());
  for (const auto& readme : readmes) {
    std::ifstream in(readme);
    for (std::string line; std::getline(in, line);) {
      const std::vector<std::string> words = words_after_concert(line);
      if (!words.empty()) add(words);
    }
  }
  // Every verb with its options.
  std::ostringstream out, err;
  cli::Cli concert("concert", "", out, err);
  tool::register_all(concert);
  std::vector<std::string> tokens;
  for (const auto& [path, app] : concert.verbs()) {
    std::vector<std::string> words;
    std::istringstream split_path(path);
    for (std::string w; split_path >> w;) words.push_back(w);
    words.erase(words.begin());  // "concert"
    for (const std::string& w : words) tokens.push_back(w);
    add(words);
    std::vector<std::string> with_help = words;
    with_help.push_back("--help");
    add(with_help);
    std::vector<std::string> all = words;
    for (const CLI::Option* o : app->get_options()) {
      // Hidden options too (the deprecated spellings): get_name() leaves those out.
      std::string name;
      if (!o->get_lnames().empty()) {
        name = "--" + o->get_lnames().front();
      } else if (!o->get_snames().empty()) {
        name = "-" + o->get_snames().front();
      }
      if (name == "--help" || name == "-h") continue;
      if (!name.empty()) {
        all.push_back(name);
        tokens.push_back(all.back());
      }
      if (o->get_items_expected_min() > 0 || name.empty()) all.push_back("1");
    }
    add(all);
  }
  seeds.add_tokens(tokens);
  seeds.add_tokens({std::string(1, '\0'), "--", "-", "=", "--help", "-h", "--help-all", "0", "-1",
                    "1e9", "nan", "inf", "1.5", "4294967296"});
}
