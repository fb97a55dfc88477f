// The restart back-off of `concert up` (Supervisor): a crash loop backs off, doubling up to the
// maximum; a service that ran for the stable time is restarted after the first delay again,
// whatever its earlier deaths were.
#include <gtest/gtest.h>
#include <signal.h>

#include <unistd.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "launcher.hpp"
#include "process.hpp"

namespace concert::tool {
namespace {

using namespace std::chrono_literals;

TEST(RestartDelay, DoublesWhileTheServiceKeepsDyingAndResetsAfterAStableRun) {
  const BackoffParams b;  // the defaults `concert up` uses
  int failures = 0;
  const auto short_run = 1s;
  EXPECT_EQ(restart_delay(b, short_run, failures), 500ms);
  EXPECT_EQ(restart_delay(b, short_run, failures), 1000ms);
  EXPECT_EQ(restart_delay(b, short_run, failures), 2000ms);
  EXPECT_EQ(restart_delay(b, short_run, failures), 4000ms);
  EXPECT_EQ(restart_delay(b, short_run, failures), 8000ms);
  EXPECT_EQ(restart_delay(b, short_run, failures), 10000ms);
  for (int i = 0; i < 40; ++i) EXPECT_EQ(restart_delay(b, short_run, failures), 10000ms);
  // A run as long as `stable`: the next death is the first of a new series.
  EXPECT_EQ(restart_delay(b, b.stable, failures), 500ms);
  EXPECT_EQ(restart_delay(b, 0s, failures), 1000ms);
  EXPECT_EQ(restart_delay(b, 10min, failures), 500ms);
}

/// Waits (bounded) until `log` contains `text`.
bool logged(Supervisor& s, const std::ostringstream& log, const std::string& text,
            std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (log.str().find(text) == std::string::npos) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    s.poll();
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

TEST(Supervisor, BacksOffACrashLoopAndRestartsAKilledStableServiceAtOnce) {
  testing::TempDir dir("concert-supervisor-test");
  std::ostringstream log;
  const BackoffParams b{.first = 100ms, .max = 400ms, .stable = 1s};
  Supervisor s({{"crasher", {"/bin/sh", "-c", "exit 3"}}, {"sleeper", {"/bin/sleep", "60"}}},
               dir.path(), log, b);
  s.start_all();
  // The crash loop: 0.1, 0.2, 0.4, 0.4 s.
  EXPECT_TRUE(logged(s, log, "crasher exited with code 3; restarting in 0.1 s (restart 1", 5s)) << log.str();
  EXPECT_TRUE(logged(s, log, "crasher exited with code 3; restarting in 0.2 s (restart 2", 5s)) << log.str();
  EXPECT_TRUE(logged(s, log, "crasher exited with code 3; restarting in 0.4 s (restart 3", 5s)) << log.str();
  EXPECT_TRUE(logged(s, log, "crasher exited with code 3; restarting in 0.4 s (restart 4", 5s)) << log.str();

  // The sleeper runs longer than `stable`, is killed: restarted after the first delay; killed
  // again at once: the delay doubles; killed after a stable run: the first delay again.
  auto kill_and_wait_restart = [&](const std::string& expected) {
    const auto pid = s.pid("sleeper");
    ASSERT_TRUE(pid.has_value()) << log.str();
    ASSERT_EQ(::kill(*pid, SIGKILL), 0);
    EXPECT_TRUE(logged(s, log, expected, 5s)) << log.str();
    for (int i = 0; i < 500 && s.pid("sleeper").value_or(*pid) == *pid; ++i) {
      s.poll();
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_NE(s.pid("sleeper").value_or(*pid), *pid) << "not restarted\n" << log.str();
  };
  const auto stable_run = [&] {
    for (int i = 0; i < 120; ++i) {  // 1.2 s, polled
      s.poll();
      std::this_thread::sleep_for(10ms);
    }
  };
  stable_run();
  kill_and_wait_restart("sleeper was killed by signal 9; restarting in 0.1 s (restart 1");
  kill_and_wait_restart("sleeper was killed by signal 9; restarting in 0.2 s (restart 2");
  stable_run();
  kill_and_wait_restart("sleeper was killed by signal 9; restarting in 0.1 s (restart 3");
  s.stop_all(2000ms);
}

// Whether `pid` runs (a zombie waiting for its reaper does not).
bool alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return false;
  const auto paren = line.rfind(')');
  return paren != std::string::npos && paren + 2 < line.size() && line[paren + 2] != 'Z';
}

TEST(Supervisor, AKilledConcertUpTakesItsServicesAlong) {
  // `concert up` killed with SIGKILL cannot stop its services: they get SIGTERM from the kernel
  // (a test ending at an assertion left a whole stack running before).
  testing::TempDir dir("concert-supervisor-orphans");
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t up = fork();
  ASSERT_GE(up, 0);
  if (up == 0) {
    std::ostringstream log;
    Supervisor s({{"sleeper", {"/bin/sleep", "60"}}}, dir.path(), log, BackoffParams{});
    s.start_all();
    const pid_t service = s.pid("sleeper").value_or(-1);
    (void)!write(fds[1], &service, sizeof service);
    pause();
    _exit(0);
  }
  pid_t service = -1;
  ASSERT_EQ(read(fds[0], &service, sizeof service), static_cast<ssize_t>(sizeof service));
  ASSERT_GT(service, 0);
  EXPECT_TRUE(alive(service));
  ASSERT_EQ(::kill(up, SIGKILL), 0);
  waitpid(up, nullptr, 0);
  bool gone = false;
  for (int i = 0; i < 500 && !gone; ++i) {  // 5 s at most
    gone = !alive(service);
    if (!gone) std::this_thread::sleep_for(10ms);
  }
  EXPECT_TRUE(gone) << "the service outlived concert up";
  if (!gone) ::kill(service, SIGKILL);
  close(fds[0]);
  close(fds[1]);
}

}  // namespace
}  // namespace concert::tool
