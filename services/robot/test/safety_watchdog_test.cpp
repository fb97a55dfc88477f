// The robot's side of the safety layer: silence from the safety service is a stop.
#include "robot/safety_watchdog.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

namespace concert::robot {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using Clock = SafetyWatchdog::Clock;

TEST(SafetyWatchdog, WithoutATimeoutNothingIsRequired) {
  const Clock::time_point t0{};
  SafetyWatchdog w(0.0, t0);
  EXPECT_FALSE(w.required());
  EXPECT_FALSE(w.silence(t0 + 1h).has_value());
}

TEST(SafetyWatchdog, HoldsUntilFirstHeardThenWhenSilentLongerThanTheBound) {
  const Clock::time_point t0{};
  SafetyWatchdog w(1.0, t0);
  ASSERT_TRUE(w.required());
  // Never heard: a stop from the first instant, however short the wait.
  ASSERT_TRUE(w.silence(t0).has_value());
  EXPECT_THAT(*w.silence(t0 + 3s), HasSubstr("not heard yet (3.00 s since the start)"));
  w.heard(t0 + 3s);
  EXPECT_FALSE(w.silence(t0 + 3s).has_value());
  EXPECT_FALSE(w.silence(t0 + 4s).has_value());  // exactly the bound: still heard
  const auto late = w.silence(t0 + 4s + 200ms);
  ASSERT_TRUE(late.has_value());
  EXPECT_THAT(*late, HasSubstr("not heard for 1.20 s (bound 1.00 s)"));
  // Heard again: fresh again. A message handled late (an older time) does not age it.
  w.heard(t0 + 5s);
  w.heard(t0 + 4500ms);
  EXPECT_FALSE(w.silence(t0 + 5900ms).has_value());
  EXPECT_TRUE(w.silence(t0 + 6100ms).has_value());
}

TEST(SafetyWatchdog, ABadTimeoutIsRefusedWithItsValue) {
  const Clock::time_point t0{};
  try {
    SafetyWatchdog w(-0.5, t0);
    FAIL() << "a negative timeout was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("got -0.5"));
  }
  EXPECT_THROW(SafetyWatchdog(std::numeric_limits<double>::quiet_NaN(), t0), std::invalid_argument);
}

}  // namespace
}  // namespace concert::robot
