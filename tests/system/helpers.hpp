#pragma once
// Helpers of the system tests (tests/support/process.hpp waits on stdout only and does not
// tie its children's life to the test's).

#include <chrono>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"

namespace concert::system_test {

/// Waits (bounded) until the process' stderr contains `text`.
inline bool wait_for_err(const testing::Process& p, const std::string& text,
                         std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (p.err().find(text) == std::string::npos) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

/// Absolute path of a system tool (the test helper runs programs without a PATH search).
inline std::string tool(const std::string& name, const std::string& package) {
  for (const char* dir : {"/usr/sbin/", "/sbin/", "/usr/bin/", "/bin/"}) {
    if (std::filesystem::exists(dir + name)) return dir + name;
  }
  throw std::runtime_error("the '" + name + "' tool (Debian package " + package +
                           ") is not installed");
}

/// `argv` run so that it gets SIGKILL if the test process dies first (a ctest timeout kills
/// the test before its destructors run).
inline std::vector<std::string> dies_with_test(std::vector<std::string> argv) {
  argv.insert(argv.begin(), {tool("setpriv", "util-linux"), "--pdeathsig", "KILL", "--"});
  return argv;
}

// The services' logs cut to fit a CI log: each section ("--- service:" and the lines after it)
// keeps its first `head` and last `tail` lines, with a line saying how many were left out.
// ctest keeps only the first 300 kB of a failed test's output; the whole logs of a mission run
// (or of a GUI test's stack) exceed that and pushed the robot's log, gtest's summary and the account of why out of it.
inline std::string trimmed_logs(const std::string& logs, std::size_t head, std::size_t tail) {
  std::vector<std::vector<std::string>> sections(1);
  std::istringstream in(logs);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("--- ", 0) == 0 && !line.empty() && line.back() == ':') sections.emplace_back();
    sections.back().push_back(std::move(line));
  }
  std::string out;
  for (const auto& lines : sections) {
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (i == head && lines.size() > head + tail) {
        out += "  [" + std::to_string(lines.size() - head - tail) + " lines left out]\n";
        i = lines.size() - tail;
      }
      out += lines[i] + "\n";
    }
  }
  return out;
}

}  // namespace concert::system_test
