#pragma once
// The end of a drilling system test (drill_mission_test, drill_pattern_test): safety RUNNING
// expected, the services' logs printed on failure (each cut to its head and tail; whole with
// CONCERT_TEST_PRINT_LOGS), and a short account of why printed before them and last of all.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "drill_runner.hpp"

namespace concert::system_test {

// What a failed run printed last: CI shows the head and the tail of the test output, and the
// services' logs (thousands of lines) push gtest's own failure messages out of both. Printed when
// the program ends, after gtest's summary, so the tail says why.
struct FailureSummary {
  std::string text;
  ~FailureSummary() {
    if (!text.empty()) std::cout << "\n==== why the drilling test failed ====\n" << text << std::flush;
  }
};
inline FailureSummary& failure_summary() {
  static FailureSummary summary;
  return summary;
}

// The lines of `logs` that say something went wrong (at most `max`, the last ones).
inline std::string alarming_lines(const std::string& logs, std::size_t max) {
  std::vector<std::string> found;
  std::istringstream in(logs);
  for (std::string line; std::getline(in, line);) {
    std::string lower = line;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    for (const char* word : {"fail", "abort", "refus", "stop", "error", "timed out", "skipp", "lost"}) {
      if (lower.find(word) != std::string::npos) {
        found.push_back(line.substr(0, 300));
        break;
      }
    }
  }
  std::string out;
  for (std::size_t i = found.size() > max ? found.size() - max : 0; i < found.size(); ++i)
    out += "  " + found[i] + "\n";
  return out;
}

/// Expects safety RUNNING at the end of `run` and prints how odometry parted from the truth; on
/// a failure of the test so far prints the logs and keeps `summary` (the test's own account: state, holes, errors) with the alarming log lines
/// for the end of the output.
inline void expect_safety_and_report(const MissionRun& run, std::ostringstream& summary) {
  summary << "safety: " << (run.safety_running ? "RUNNING" : "not RUNNING") << "\n";
  EXPECT_TRUE(run.safety_running);
  std::cout << odometry_drift(run.track);
  // A safety stop on a joint's torque or position: what that joint carried, and where it was,
  // before it.
  std::string trace;
  if (const auto at = run.logs.find("STOPPED: limits: joint "); at != std::string::npos) {
    const std::size_t from = at + std::string("STOPPED: limits: joint ").size();
    const std::string joint = run.logs.substr(from, run.logs.find(' ', from) - from);
    if (run.logs.compare(from + joint.size(), 11, " RMS effort") == 0 ||
        run.logs.compare(from + joint.size(), 7, " effort") == 0 ||
        run.logs.compare(from + joint.size(), 9, " position") == 0)
      trace = torque_trace(run, joint);
  }
  std::cout << trace;
  const bool failed = ::testing::Test::HasFailure();
  if (failed) {
    failure_summary().text = summary.str() + odometry_drift(run.track) + trace +
                             "what the services' logs said went wrong (last 25):\n" +
                             alarming_lines(run.logs, 25);
    // First as well as last: a cut output keeps one of the two.
    std::cout << "\n==== why the drilling test failed ====\n" << failure_summary().text << std::flush;
  }
  if (std::getenv("CONCERT_TEST_PRINT_LOGS") != nullptr) {
    std::cout << run.logs << std::endl;
  } else if (failed) {
    std::cout << "\n==== the services' logs, each cut to its first 40 and last 200 lines "
                 "(CONCERT_TEST_PRINT_LOGS=1: whole) ====\n"
              << trimmed_logs(run.logs, 40, 200) << std::flush;
  }
}

}  // namespace concert::system_test
