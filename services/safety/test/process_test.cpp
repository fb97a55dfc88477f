// concert_safety as a real process over DDS: e-stop -> STOPPED, reset refused while engaged,
// released + reset -> RUNNING, a silent task service named in the stop, clean SIGINT stop;
// bad arguments and params files exit non-zero with one line naming the problem.
#include "process.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "safety/cli.hpp"
#include "test_helpers.hpp"

namespace concert::safety {
namespace {

using namespace std::chrono_literals;
using test::wait_state;

// The operator's reset after the e-stop input was released: the release and the reset travel on
// two topics with no order between them, so under load the reset can arrive first and be
// refused ("still engaged"); the operator presses again (up to 5 times, 2 s apart), as the chaos
// harness does. True once the service runs again.
bool reset_until_running(Writer<msg::SafetyReset>& resets, Reader<msg::SafetyState>& states,
                         std::uint32_t first_id) {
  for (std::uint32_t k = 0; k < 5; ++k) {
    msg::SafetyReset reset;
    reset.request_id(first_id + k);
    reset.source("process test");
    if (!resets.write(reset)) return false;
    if (wait_state(states, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 2s))
      return true;
  }
  return false;
}

std::filesystem::path temp_file(const std::string& name, const std::string& text) {
  const auto path =
      std::filesystem::temp_directory_path() / (name + "_" + std::to_string(getpid()) + ".yaml");
  std::ofstream(path) << text;
  return path;
}

TEST(SafetyProcess, EStopResetAndLivelinessOverDds) {
  const auto params =
      temp_file("safety_params", "liveliness_timeout: 0.5\ntask_services: [drill]\n");
  testing::Process safety({SAFETY_BINARY, "--params", params.string()});
  {
    Participant p({.name = "safety_process_test"});
    Reader<msg::SafetyState> states(p, topics::safety_state);
    Writer<msg::EStopInput> inputs(p, topics::estop);
    Writer<msg::SafetyReset> resets(p, topics::safety_reset);
    Writer<msg::ServiceStatus> statuses(p, topics::status);
    ASSERT_TRUE(wait_state(
        states, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 20s))
        << safety.err();
    ASSERT_TRUE(inputs.wait_for_readers(1, 10s));
    ASSERT_TRUE(resets.wait_for_readers(1, 10s));

    msg::EStopInput button;
    button.source(msg::ESTOP_BUTTON_REAR_LEFT);
    button.engaged(true);
    button.reason("pressed");
    ASSERT_TRUE(inputs.write(button));
    ASSERT_TRUE(wait_state(
        states,
        [](const auto& s) {
          return s.mode() == msg::SAFETY_STOPPED && s.reset_required() && s.causes().size() == 1 &&
                 s.causes()[0] == "estop: button rear left engaged (pressed)";
        },
        10s))
        << safety.err();

    msg::SafetyReset reset;
    reset.request_id(1);
    reset.source("process test");
    ASSERT_TRUE(resets.write(reset));
    // Refused: the state stays STOPPED through at least one more publication.
    EXPECT_FALSE(wait_state(
        states, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 1s));

    button.engaged(false);
    ASSERT_TRUE(inputs.write(button));
    EXPECT_FALSE(wait_state(
        states, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 1s));
    ASSERT_TRUE(reset_until_running(resets, states, 2)) << safety.err();

    // A drill service beats for a while, then goes silent (writer alive, no more samples).
    msg::ServiceStatus beat;
    beat.id(concert::dds::status_instance_id("drill", "manip-pc"));
    beat.service("drill");
    beat.host("manip-pc");
    beat.state(msg::SERVICE_READY);
    for (int i = 0; i < 8; ++i) {
      ASSERT_TRUE(statuses.write(beat));
      std::this_thread::sleep_for(50ms);
    }
    ASSERT_TRUE(wait_state(
        states,
        [](const auto& s) {
          return s.mode() == msg::SAFETY_STOPPED && !s.causes().empty() &&
                 s.causes()[0].find("liveliness: drill@manip-pc silent for") == 0;
        },
        10s))
        << safety.err();
  }
  EXPECT_EQ(safety.stop(15s), 0);
  const auto err = safety.err();
  EXPECT_NE(
      err.find(
          "safety: reset by process test refused: e-stop input(s) still engaged: button rear left"),
      std::string::npos)
      << err;
  EXPECT_NE(err.find("safety: reset by process test accepted: 1 cause(s) cleared"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("safety: STOPPED: liveliness: drill@manip-pc silent"), std::string::npos)
      << err;
  std::filesystem::remove(params);
}

TEST(SafetyProcess, KilledHardItComesBackWithItsLatchedStop) {
  const auto state = temp_file("safety_state", "");
  std::filesystem::remove(state);
  Participant p({.name = "safety_process_test"});
  auto stopped_by_wireless = [](const msg::SafetyState& s) {
    return s.mode() == msg::SAFETY_STOPPED && s.causes().size() == 1 &&
           s.causes()[0] == "estop: wireless engaged (operator)";
  };
  {
    // The input's writer goes with this block: its latched "engaged" sample would otherwise
    // reach every later safety process, and the stop they hold must come from the state file.
    Writer<msg::EStopInput> inputs(p, topics::estop);
    testing::Process safety({SAFETY_BINARY, "--state", state.string()});
    Reader<msg::SafetyState> states(p, topics::safety_state);
    ASSERT_TRUE(wait_state(
        states, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 20s))
        << safety.err();
    ASSERT_TRUE(inputs.wait_for_readers(1, 10s));
    msg::EStopInput wireless;
    wireless.source(msg::ESTOP_WIRELESS);
    wireless.engaged(true);
    wireless.reason("operator");
    ASSERT_TRUE(inputs.write(wireless));
    ASSERT_TRUE(wait_state(states, stopped_by_wireless, 10s)) << safety.err();
    ASSERT_EQ(::kill(safety.pid(), SIGKILL), 0);
    ASSERT_TRUE(safety.wait(10s).has_value());
  }
  // The test writes the input no more, yet the restarted service still holds the stop and the
  // input engaged. The operator's writers are a fresh participant's: this one still counts the
  // killed process' readers as matched until their lease ends (5 s), and a command written to
  // them only is lost.
  testing::Process again({SAFETY_BINARY, "--state", state.string()});
  {
    Participant operator_panel({.name = "safety_process_test_panel"});
    Writer<msg::EStopInput> panel_inputs(operator_panel, topics::estop);
    Writer<msg::SafetyReset> panel_resets(operator_panel, topics::safety_reset);
    Reader<msg::SafetyState> states(operator_panel, topics::safety_state);
    ASSERT_TRUE(wait_state(states, stopped_by_wireless, 20s)) << again.err();
    ASSERT_TRUE(panel_resets.wait_for_readers(1, 10s));
    ASSERT_TRUE(panel_inputs.wait_for_readers(1, 10s));
    msg::SafetyReset reset;
    reset.request_id(1);
    reset.source("process test");
    ASSERT_TRUE(panel_resets.write(reset));
    EXPECT_FALSE(wait_state(
        states, [](const auto& s) { return s.mode() == msg::SAFETY_RUNNING; }, 1s));
    msg::EStopInput released;
    released.source(msg::ESTOP_WIRELESS);
    released.engaged(false);
    ASSERT_TRUE(panel_inputs.write(released));
    std::this_thread::sleep_for(200ms);
    ASSERT_TRUE(reset_until_running(panel_resets, states, 2)) << again.err();
  }
  EXPECT_EQ(again.stop(15s), 0);
  EXPECT_NE(again.err().find("safety: restored from " + state.string() +
                             ": STOPPED: estop: wireless engaged (operator)"),
            std::string::npos)
      << again.err();
  EXPECT_NE(again.err().find("refused: e-stop input(s) still engaged: wireless"), std::string::npos)
      << again.err();

  // A state file that cannot be read: stopped, naming it, until an operator reset.
  std::ofstream(state, std::ios::trunc) << "mode: [broken\n";
  testing::Process broken({SAFETY_BINARY, "--state", state.string()});
  {
    Participant fresh({.name = "safety_process_test_fresh"});
    Reader<msg::SafetyState> states(fresh, topics::safety_state);
    EXPECT_TRUE(wait_state(
        states,
        [&](const auto& s) {
          return s.mode() == msg::SAFETY_STOPPED && s.causes().size() == 1 &&
                 s.causes()[0].find("safety: the latched state could not be read back: " +
                                    state.string()) == 0;
        },
        20s))
        << broken.err();
  }
  EXPECT_EQ(broken.stop(15s), 0);
  std::filesystem::remove(state);
}

/// Runs `concert safety <args>` in this process; returns (code, stdout + stderr).
std::pair<int, std::string> cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  std::vector<std::string> full = args;
  full.insert(full.begin(), "safety");
  const int code = cli::run("concert", {register_verbs}, full, out, err);
  return {code, out.str() + err.str()};
}

TEST(SafetyProcess, OperatorVerbsEStopStatusReset) {
  testing::Process safety({SAFETY_BINARY});
  auto [code, text] = cli({"status", "--timeout", "20"});
  ASSERT_EQ(code, 0) << text << safety.err();
  EXPECT_EQ(text, "safety: RUNNING\n");

  std::tie(code, text) = cli({"estop", "--source", "wireless", "--reason", "operator walked away"});
  ASSERT_EQ(code, 0) << text;
  EXPECT_EQ(text, "safety: e-stop wireless engaged\n");
  std::tie(code, text) = cli({"status"});
  EXPECT_EQ(code, 0);
  EXPECT_NE(text.find("STOPPED (reset required)\n  estop: wireless engaged (operator walked away)"),
            std::string::npos)
      << text;

  std::tie(code, text) = cli({"reset", "--source", "operator panel"});
  EXPECT_EQ(code, 1) << text;
  EXPECT_NE(text.find("concert safety reset: reset by operator panel refused: e-stop input(s) "
                      "still engaged: wireless"),
            std::string::npos)
      << text;

  std::tie(code, text) = cli({"estop", "--source", "wireless", "--release"});
  EXPECT_EQ(code, 0) << text;
  std::tie(code, text) = cli({"reset"});
  EXPECT_EQ(code, 0) << text << safety.err();
  EXPECT_EQ(text, "safety: RUNNING\n");
  EXPECT_EQ(safety.stop(15s), 0);
}

/// A command line that must fail: its arguments, the exit code and a text its output names.
struct Failing {
  std::vector<std::string> args;
  int code;
  std::string text;
};

/// Runs every command line of `failing` through `run` (which returns the exit code and the
/// output) and checks how each ends.
void expect_failures(
    const std::function<std::pair<int, std::string>(std::vector<std::string>)>& run,
    const std::vector<Failing>& failing) {
  for (const auto& f : failing) {
    const auto [code, text] = run(f.args);
    EXPECT_EQ(code, f.code) << ::testing::PrintToString(f.args) << ": " << text;
    EXPECT_NE(text.find(f.text), std::string::npos) << text;
  }
}

TEST(SafetyCli, UsageErrorsAndNoService) {
  expect_failures(
      cli,
      {{{}, 2, "concert safety: missing verb (one of: status, estop, reset)"},
       {{"estop", "--source", "left"},
        2,
        "--source: left not in {front-left,front-right,rear-left,rear-right,software,wireless}"},
       {{"status", "--timeout", "soon"}, 2, "--timeout: 'soon' is not a number >= 0"},
       {{"status", "--release"},
        2,
        "concert safety status: The following argument was not expected: --release"},
       // No safety service running.
       {{"reset", "--timeout", "0.3"}, 1, "concert safety reset: no safety service on domain"}});
}

/// Runs concert_safety with `args`; returns (exit code, stderr).
std::pair<int, std::string> run(std::vector<std::string> args) {
  args.insert(args.begin(), SAFETY_BINARY);
  testing::Process p(args);
  const auto code = p.wait(15s);
  return {code.value_or(-1), p.err()};
}

TEST(SafetyProcess, BadArgumentsExitNonZeroWithOneLine) {
  const auto bad = temp_file("safety_bad", "liveliness_timeout: soon\n");
  expect_failures(
      run, {{{"--bogus"}, 2, "concert_safety: The following argument was not expected: --bogus"},
            {{"--params"}, 2, "--params: 1 required FILE missing"},
            {{"--params", "/nonexistent/safety.yaml"},
             1,
             "parameters file '/nonexistent/safety.yaml' cannot be opened"},
            {{"--params", bad.string()},
             1,
             bad.string() + ": liveliness_timeout: expected a duration in seconds in (0, 3600], "
                            "got 'soon' (line 1)"}});
  std::filesystem::remove(bad);
}

}  // namespace
}  // namespace concert::safety
