#include "gui/rate_limiter.hpp"

#include <gtest/gtest.h>

namespace concert::gui {
namespace {

constexpr int64_t kMs = 1'000'000;

TEST(RateLimiter, AOneKilohertzStreamLimitedToTenHertzPassesTenASecond) {
  RateLimiter limiter(10.0);
  int sent = 0;
  for (int64_t i = 0; i < 1000; ++i) sent += limiter.admit(i * kMs) ? 1 : 0;
  EXPECT_EQ(sent, 10);
  EXPECT_EQ(limiter.dropped(), 990u);
}

TEST(RateLimiter, JitteredArrivalsKeepTheCadence) {
  // 30 Hz source with ±3 ms jitter, limited to 10 Hz: 10 a second, not 7 or 8.
  RateLimiter limiter(10.0);
  int sent = 0;
  for (int64_t i = 0; i < 300; ++i) {
    const int64_t jitter = (i % 3 - 1) * 3 * kMs;
    sent += limiter.admit(i * 33'333'333 + jitter) ? 1 : 0;
  }
  EXPECT_GE(sent, 95);
  EXPECT_LE(sent, 101);
}

TEST(RateLimiter, AfterAPauseTheNextSampleGoesAtOnceWithoutABurst) {
  RateLimiter limiter(10.0);
  EXPECT_TRUE(limiter.admit(0));
  EXPECT_TRUE(limiter.admit(5000 * kMs));
  EXPECT_FALSE(limiter.admit(5001 * kMs));
  EXPECT_FALSE(limiter.admit(5050 * kMs));
  EXPECT_TRUE(limiter.admit(5100 * kMs));
}

TEST(RateLimiter, ZeroMeansNoLimit) {
  RateLimiter limiter(0.0);
  for (int i = 0; i < 100; ++i) EXPECT_TRUE(limiter.admit(i));
}

TEST(RateMeter, MeasuresTheRateOverItsWindowAndForgetsOldSamples) {
  RateMeter meter(2000 * kMs);
  EXPECT_EQ(meter.hz(0), 0.0);
  for (int64_t i = 0; i < 200; ++i) meter.add(i * 10 * kMs);  // 100 Hz for 2 s
  EXPECT_NEAR(meter.hz(1990 * kMs), 100.0, 0.6);
  EXPECT_EQ(meter.count(), 200u);
  EXPECT_EQ(meter.hz(10'000 * kMs), 0.0);  // stopped long ago
}

TEST(RateMeter, AboveItsCapacityTheRateIsStillRight) {
  RateMeter meter(2000 * kMs);
  for (int64_t i = 0; i < 20'000; ++i) meter.add(i * kMs / 4);  // 4 kHz
  EXPECT_NEAR(meter.hz(20'000 * kMs / 4), 4000.0, 5.0);
}

}  // namespace
}  // namespace concert::gui
