// The whole `concert` command line, walked from its CLI11 tree: every verb and group answers
// --help with exit 0, a group without its verb exits 2, and every verb that talks DDS accepts
// the common options. A verb registered later is covered without editing this test.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>
#include <sstream>

#include "concert/common/text.hpp"
#include "process.hpp"
#include "verbs.hpp"

namespace concert {
namespace {

using ::testing::HasSubstr;

using namespace std::chrono_literals;

struct Outcome {
  int code;
  std::string out, err;
};

/// Runs `args` through a fresh command line with every verb registered (in this process).
Outcome run(const std::vector<std::string>& args, bool parse_only = false) {
  std::ostringstream out, err;
  cli::Cli concert("concert", "", out, err);
  tool::register_all(concert);
  const int code = parse_only ? concert.parse_only(args) : concert.run(args);
  return {code, out.str(), err.str()};
}

/// Every command of the tree (groups and verbs) as its words after "concert".
std::vector<std::vector<std::string>> all_commands(bool groups, bool verbs) {
  std::ostringstream out, err;
  cli::Cli concert("concert", "", out, err);
  tool::register_all(concert);
  // A verb may have verbs of its own (`concert gui` serves, `concert gui users add` manages its
  // users): it is a verb, not a group.
  std::set<std::string> runnable;
  for (const auto& [name, app] : concert.verbs()) runnable.insert(name);
  std::vector<std::vector<std::string>> found;
  std::function<void(CLI::App&, std::vector<std::string>)> walk =
      [&](CLI::App& app, std::vector<std::string> path) {
        const auto subs = app.get_subcommands([](CLI::App*) { return true; });
        const bool verb = subs.empty() || runnable.count("concert " + join(path, " ")) > 0;
        if (!path.empty() && ((verb && verbs) || (!verb && groups))) found.push_back(path);
        for (CLI::App* sub : subs) {
          auto next = path;
          next.push_back(sub->get_name());
          walk(*sub, next);
        }
      };
  walk(concert.app(), {});
  return found;
}

TEST(ConcertCli, TheTreeHasTheVerbsOfTheBuiltServices) {
  std::set<std::string> names;
  for (const auto& path : all_commands(false, true)) names.insert(join(path, " "));
  for (const char* verb :
       {"up", "status", "sim swap", "sim world", "topic list", "topic info", "topic echo",
        "topic hz", "topic pub", "bag record", "bag info", "bag play", "scan show", "scan read", "scan publish", "help"}) {
    EXPECT_TRUE(names.count(verb)) << verb << " missing from " << join(names);
  }
  EXPECT_GE(names.size(), 12u);
}

TEST(ConcertCli, HelpOnEveryVerbAndGroupExitsZero) {
  for (auto path : all_commands(true, true)) {
    const std::string name = "concert " + join(path, " ");
    path.push_back("--help");
    const Outcome r = run(path);
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    EXPECT_THAT(r.out, HasSubstr("Usage: " + name)) << name << ":\n" << r.out;
    EXPECT_TRUE(r.err.empty()) << name << ": " << r.err;
  }
  const Outcome top = run({"--help"});
  EXPECT_EQ(top.code, 0);
  EXPECT_THAT(top.out, HasSubstr("Exit codes: 0 success"));
  const Outcome help = run({"help", "topic", "echo"});
  EXPECT_EQ(help.code, 0) << help.err;
  EXPECT_THAT(help.out, HasSubstr("Usage: concert topic echo"));
}

TEST(ConcertCli, AGroupWithoutItsVerbExitsTwoNamingTheVerbs) {
  for (const auto& path : all_commands(true, false)) {
    const Outcome r = run(path);
    EXPECT_EQ(r.code, 2) << join(path, " ");
    EXPECT_NE(r.err.find("missing verb (one of: "), std::string::npos)
        << join(path, " ") << ": " << r.err;
  }
  const Outcome none = run({});
  EXPECT_EQ(none.code, 2);
  EXPECT_THAT(none.out, HasSubstr("Usage: concert")) << "no arguments: the help";
  const Outcome unknown = run({"frobnicate"});
  EXPECT_EQ(unknown.code, 2);
  EXPECT_THAT(unknown.err, HasSubstr("unknown verb 'frobnicate'"));
}

/// Values for a verb's required arguments that pass its checks (numbers where numbers go).
std::vector<std::string> required_arguments(const CLI::App& verb) {
  std::vector<std::string> args;
  for (const CLI::Option* o : verb.get_options()) {
    if (!o->get_required()) continue;
    if (!o->get_positional()) args.push_back(o->get_name());
    for (int i = 0; i < std::max(1, o->get_items_expected_min()); ++i) args.push_back("1");
  }
  return args;
}

/// Verbs that act on a domain without talking DDS themselves (they start processes or write
/// the run folder); every other verb with --domain must take the DDS options.
const std::set<std::string> kDomainOnly = {"concert up"};
/// Extra arguments for verbs whose rules are checked after parsing.
const std::map<std::string, std::vector<std::string>> kExtra = {
    {"concert scan publish", {"--scan", "scan.yaml"}}};

TEST(ConcertCli, EveryVerbThatTalksDdsAcceptsDomainTimeoutAndJson) {
  std::ostringstream out, err;
  cli::Cli concert("concert", "", out, err);
  tool::register_all(concert);
  int dds_verbs = 0;
  for (const auto& [name, verb] : concert.verbs()) {
    if (verb->get_option_no_throw("--domain") == nullptr) continue;
    if (kDomainOnly.count(name)) continue;
    EXPECT_TRUE(concert.talks_dds(*verb)) << name << " takes --domain but not the DDS options";
    for (const char* option : {"--domain", "--timeout", "--json"}) {
      EXPECT_NE(verb->get_option_no_throw(option), nullptr) << name << " lacks " << option;
    }
    std::vector<std::string> args = split(name, ' ');
    args.erase(args.begin());
    const auto required = required_arguments(*verb);
    args.insert(args.end(), required.begin(), required.end());
    if (const auto extra = kExtra.find(name); extra != kExtra.end()) {
      args.insert(args.end(), extra->second.begin(), extra->second.end());
    }
    for (const char* option : {"--domain", "7", "--timeout", "1.5", "--json"})
      args.push_back(option);
    const Outcome r = run(args, true);
    EXPECT_EQ(r.code, 0) << name << " " << join(args, " ") << ": " << r.err;
    ++dds_verbs;
  }
  EXPECT_GE(dds_verbs, 6) << "topic list/info/echo/hz/pub, status, scan publish at least";
}

TEST(ConcertCli, WrongOptionsExitTwoNamingTheOption) {
  Outcome r = run({"topic", "echo", "a/b", "--domain", "999"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--domain: '999' is not a DDS domain id (an integer from 0 to 232)"));
  r = run({"status", "--timeout", "soon"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("concert status: --timeout: 'soon' is not a number >= 0"));
  r = run({"scan", "show"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("give exactly one of --scan FILE or --assembly FILE"));
}

TEST(ConcertCli, TheExecutableUsesTheSameExitCodes) {
  testing::Process help({CONCERT_BIN, "sim", "--help"});
  EXPECT_EQ(help.wait(30s), 0);
  EXPECT_THAT(help.out(), HasSubstr("Usage: concert sim"));
  testing::Process missing({CONCERT_BIN, "sim"});
  EXPECT_EQ(missing.wait(30s), 2);
  EXPECT_THAT(missing.err(), HasSubstr("concert sim: missing verb (one of: assemble, swap, world, person)"));
}

}  // namespace
}  // namespace concert
