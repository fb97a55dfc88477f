#include "concert/cli/cli.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace concert::cli {
namespace {

/// A small command line like the concert tool's: a group with a DDS verb, and a plain verb.
struct Tool {
  std::ostringstream out, err;
  Cli cli{"tool", "a test tool", out, err};
  DdsOptions dds;
  std::string name;
  long count = 0;
  double wait_s = 1.5;
  int ran = 0;

  Tool() {
    CLI::App& topic = cli.group(cli.app(), "topic", "topics");
    CLI::App& echo = cli.verb(topic, "echo", "print samples", [this] {
      ++ran;
      out << "echo " << name << " domain " << dds.domain_id() << " timeout " << dds.timeout_s
          << (dds.json ? " json" : "") << (dds.timeout_given ? " given" : "");
      return 0;
    });
    echo.add_option("NAME", name, "topic name")->required();
    echo.add_option("--count", count, "samples")->check(cli::count());
    cli.add_dds_options(echo, dds, 3.0, "how long to wait for the samples");
    Cli::add_seconds_option(echo, "--wait", "--wait-ms", wait_s, "discovery wait");
    cli.verb(cli.app(), "fail", "always fails", []() -> int { throw Failure("no such thing"); });
    cli.verb(cli.app(), "misuse", "a bad combination",
             []() -> int { throw UsageError("give exactly one of --a or --b"); });
  }

  int run(const std::vector<std::string>& args) {
    out.str("");
    err.str("");
    return cli.run(args);
  }
};

TEST(Cli, RunsTheChosenVerbWithItsOptions) {
  Tool t;
  EXPECT_EQ(t.run({"topic", "echo", "a/b", "--count", "3", "--domain", "7", "--json"}), 0)
      << t.err.str();
  EXPECT_EQ(t.out.str(), "echo a/b domain 7 timeout 3 json");
  EXPECT_EQ(t.count, 3);
  Tool u;
  EXPECT_EQ(u.run({"topic", "echo", "x", "--timeout", "0.5", "--domain", "1"}), 0);
  EXPECT_EQ(u.out.str(), "echo x domain 1 timeout 0.5 given");
}

TEST(Cli, DeprecatedMillisecondSpellingsStillWork) {
  Tool t;
  EXPECT_EQ(
      t.run({"topic", "echo", "x", "--timeout-ms", "1500", "--wait-ms", "250", "--domain", "0"}), 0)
      << t.err.str();
  EXPECT_EQ(t.dds.timeout_s, 1.5);
  EXPECT_EQ(t.wait_s, 0.25);
  Tool u;
  EXPECT_EQ(u.run({"topic", "echo", "--help"}), 0);
  EXPECT_EQ(u.out.str().find("Excludes"), std::string::npos)
      << "hidden spellings leak: " << u.out.str();
}

TEST(Cli, HelpExitsZeroOnEveryLevel) {
  Tool t;
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--help"},
                                               {"topic", "--help"},
                                               {"topic", "echo", "--help"},
                                               {"fail", "-h"}}) {
    EXPECT_EQ(t.run(args), 0) << t.err.str();
    EXPECT_NE(t.out.str().find("Usage"), std::string::npos) << t.out.str();
    EXPECT_EQ(t.run(args), 0);
  }
  t.run({"topic", "echo", "--help"});
  EXPECT_NE(t.out.str().find("--timeout"), std::string::npos) << t.out.str();
  EXPECT_EQ(t.out.str().find("--timeout-ms"), std::string::npos) << "deprecated spelling shown";
  EXPECT_EQ(t.ran, 0);
}

TEST(Cli, WrongCommandLinesExitTwoNamingTheOption) {
  Tool t;
  EXPECT_EQ(t.run({"topic", "echo", "x", "--count", "y"}), 2);
  EXPECT_EQ(t.err.str(),
            "tool topic echo: --count: 'y' is not a whole number >= 0 (see `tool topic echo "
            "--help`)\n");
  EXPECT_EQ(t.run({"topic", "echo", "x", "--domain", "999"}), 2);
  EXPECT_NE(t.err.str().find("--domain: '999' is not a DDS domain id (an integer from 0 to 232)"),
            std::string::npos)
      << t.err.str();
  EXPECT_EQ(t.run({"topic", "echo", "x", "--timeout", "-1"}), 2);
  EXPECT_NE(t.err.str().find("--timeout: '-1' is not a number >= 0"), std::string::npos);
  EXPECT_EQ(t.run({"topic", "echo", "x", "--bogus"}), 2);
  EXPECT_NE(t.err.str().find("--bogus"), std::string::npos) << t.err.str();
  EXPECT_EQ(t.run({"topic", "echo"}), 2);
  EXPECT_NE(t.err.str().find("NAME is required"), std::string::npos) << t.err.str();
  EXPECT_EQ(t.run({"topic"}), 2);
  EXPECT_EQ(t.err.str(), "tool topic: missing verb (one of: echo) (see `tool topic --help`)\n");
  EXPECT_EQ(t.run({"topic", "frob"}), 2);
  EXPECT_EQ(t.err.str(),
            "tool topic: unknown verb 'frob' (one of: echo) (see `tool topic --help`)\n");
  EXPECT_EQ(t.run({"misuse"}), 2);
  EXPECT_EQ(t.err.str(),
            "tool misuse: give exactly one of --a or --b (see `tool misuse --help`)\n");
  EXPECT_EQ(t.run({}), 2);
  EXPECT_NE(t.out.str().find("Usage"), std::string::npos) << "no arguments: the help";
  EXPECT_EQ(t.ran, 0);
}

TEST(Cli, FailuresExitOne) {
  Tool t;
  EXPECT_EQ(t.run({"fail"}), 1);
  EXPECT_EQ(t.err.str(), "tool fail: no such thing\n");
}

TEST(Cli, ParseOnlyAndTheVerbTree) {
  Tool t;
  EXPECT_EQ(t.cli.parse_only({"topic", "echo", "x", "--json", "--timeout", "2", "--domain", "3"}),
            0);
  EXPECT_EQ(t.ran, 0);
  const auto verbs = t.cli.verbs();
  ASSERT_EQ(verbs.size(), 3u);
  EXPECT_EQ(verbs[0].first, "tool topic echo");
  EXPECT_TRUE(t.cli.talks_dds(*verbs[0].second));
  EXPECT_EQ(verbs[1].first, "tool fail");
  EXPECT_FALSE(t.cli.talks_dds(*verbs[1].second));
}

TEST(Cli, DomainFromTheEnvironment) {
  Tool t;
  setenv("CONCERT_DOMAIN_ID", "42", 1);
  EXPECT_EQ(t.run({"topic", "echo", "x"}), 0);
  EXPECT_EQ(t.out.str(), "echo x domain 42 timeout 3");
  setenv("CONCERT_DOMAIN_ID", "abc", 1);
  EXPECT_EQ(t.run({"topic", "echo", "x"}), 2);
  EXPECT_NE(t.err.str().find("CONCERT_DOMAIN_ID: 'abc' is not a DDS domain id"), std::string::npos)
      << t.err.str();
  unsetenv("CONCERT_DOMAIN_ID");
}

}  // namespace
}  // namespace concert::cli
