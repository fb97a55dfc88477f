#pragma once
// Test helper: run a program as a child process with its output in a file, wait with a time
// bound, and kill it if it overstays. Shared by contract, integration and system tests.

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace concert::testing {

/// A fresh folder /tmp/<prefix>-XXXXXX, removed with its content when this goes.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

class Process {
 public:
  /// Starts argv[0] with the arguments; stdout and stderr go to files in a fresh temp folder.
  /// `env` entries ("NAME=value") are added to the environment.
  explicit Process(std::vector<std::string> argv, std::vector<std::string> env = {});
  /// Stops the process if still running: SIGINT, SIGKILL 5 s later.
  ~Process();
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  /// Exit code, or nullopt if it did not end within `timeout` (it is then still running).
  std::optional<int> wait(std::chrono::milliseconds timeout);
  /// Sends SIGINT and waits up to `timeout`; SIGKILL after that. Returns the exit code, or -signal.
  int stop(std::chrono::milliseconds timeout);
  bool running();

  std::string out() const;  ///< stdout so far
  std::string err() const;  ///< stderr so far
  /// Waits until stdout contains `text` (or the process ends); true if found.
  bool wait_for_output(const std::string& text, std::chrono::milliseconds timeout);
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  TempDir dir_{"concert-proc"};
};

/// How a program run to its end went: exit code (-1: it did not end in time and was killed),
/// stdout and stderr.
struct Outcome {
  int code;
  std::string out, err;
};

/// Runs argv to its end, at most `timeout` (then it is killed); `env` as for Process.
Outcome run(std::vector<std::string> argv, std::chrono::milliseconds timeout,
            std::vector<std::string> env = {});

/// Lines of `text`.
std::vector<std::string> lines(const std::string& text);

}  // namespace concert::testing
