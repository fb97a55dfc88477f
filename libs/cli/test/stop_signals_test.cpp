#include "concert/cli/stop_signals.hpp"

#include <gtest/gtest.h>

#include <csignal>

namespace concert::cli {
namespace {

std::atomic<int> g_last_signal{0};

void remember(int signal) { g_last_signal = signal; }

// raise() returns after the handler ran (the signal is delivered to the calling thread).
TEST(StopSignals, BothSignalsReachTheHandler) {
  on_stop_signals(remember);
  ASSERT_EQ(std::raise(SIGINT), 0);
  EXPECT_EQ(g_last_signal.load(), SIGINT);
  ASSERT_EQ(std::raise(SIGTERM), 0);
  EXPECT_EQ(g_last_signal.load(), SIGTERM);
}

TEST(StopSignals, TheFlagIsSetBySigterm) {
  const std::atomic<bool>& stop = stop_on_signals();
  EXPECT_FALSE(stop.load());
  ASSERT_EQ(std::raise(SIGTERM), 0);
  EXPECT_TRUE(stop.load());
  EXPECT_EQ(&stop_on_signals(), &stop);  // one flag for the process
}

}  // namespace
}  // namespace concert::cli
