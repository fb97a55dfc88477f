#include "robot/loop.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace concert::robot {
namespace {

TEST(Loop, RunsTheRequestedTicksAsFastAsPossible) {
  int ticks = 0;
  Loop loop({0.001, false, true}, [&] { ++ticks; });
  const LoopStats stats = loop.run(500);
  EXPECT_EQ(ticks, 500);
  EXPECT_EQ(stats.cycles, 500u);
  EXPECT_LT(stats.wall_time, 0.4);  // 500 ms of loop time would mean it slept
}

TEST(Loop, RealTimeKeepsThePeriodOnAverage) {
  int ticks = 0;
  Loop loop({0.002, true, true}, [&] { ++ticks; });
  const LoopStats stats = loop.run(100);
  EXPECT_EQ(ticks, 100);
  // Absolute deadlines: 100 ticks take at least 99 periods, whatever the machine load.
  EXPECT_GE(stats.wall_time, 99 * 0.002 * 0.999);
  EXPECT_GT(stats.mean_period, 0.0);
  EXPECT_GE(stats.p99_period, stats.mean_period * 0.5);
}

TEST(Loop, StopsFromAnotherThread) {
  std::atomic<int> ticks{0};
  Loop loop({0.001, true, false}, [&] { ++ticks; });
  std::thread stopper([&] {
    for (int i = 0; i < 2000 && ticks.load() < 20; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    loop.stop();
  });
  const LoopStats stats = loop.run_forever();
  stopper.join();
  EXPECT_GE(stats.cycles, 20u);
  EXPECT_LT(stats.cycles, 100000u);
}

TEST(Loop, RejectsBadPeriod) { EXPECT_THROW(Loop({0.0, false, false}, [] {}), std::invalid_argument); }

}  // namespace
}  // namespace concert::robot
