// The odometry EKF on a seeded simulated drive: wheel odometry that skids in turns (a yaw-rate
// slip bias) and a gyro with a constant bias.
#include "nav/odometry_filter.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace concert::nav {
namespace {

using ::testing::HasSubstr;

double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

// Base twist (vx, vy, wz) of the drive at time t [s]: at rest, straight runs, turns in place,
// arcs and a sideways move (omni-steering), 90 s in all, always turning left (~ 14 rad).
Eigen::Vector3d true_twist(double t) {
  if (t < 10.0) return {0, 0, 0};
  if (t < 20.0) return {0.5, 0, 0};
  if (t < 26.0) return {0, 0, 0.5};
  if (t < 41.0) return {0.4, 0, 0.25};
  if (t < 44.0) return {0, 0, 0};
  if (t < 50.0) return {0, 0, 0.5};
  if (t < 60.0) return {0.5, 0, 0};
  if (t < 66.0) return {0, 0.3, 0};
  if (t < 80.0) return {0.3, 0, 0.3};
  return {0.5, 0, 0};
}

struct DriveResult {
  double filter_yaw_error_max{0.0};
  double wheel_yaw_error_max{0.0};
  double filter_yaw_error_end{0.0};
  double wheel_yaw_error_end{0.0};
  double filter_position_error_end{0.0};
  double wheel_position_error_end{0.0};
  double bias_error_end{0.0};
  double bias_sigma_end{0.0};
};

DriveResult simulate_drive(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  constexpr double kDt = 0.005;    // gyro at 200 Hz, wheels at 100 Hz
  constexpr double kSlip = 0.08;   // the wheels report 8 % more yaw rate than the base turns
  constexpr double kScale = 0.01;  // and 1 % more distance
  const double gyro_bias = 0.006;  // [rad/s], about the BMI055's zero-rate offset / 3
  const double gyro_sigma = 2.44e-4 * std::sqrt(200.0);  // white noise per sample [rad/s]

  OdometryFilter filter;
  filter.reset(0.0);
  Eigen::Vector3d truth = Eigen::Vector3d::Zero();
  Eigen::Vector3d wheel_only = Eigen::Vector3d::Zero();
  DriveResult r;
  auto integrate = [](Eigen::Vector3d& pose, const Eigen::Vector3d& twist, double dt) {
    const double c = std::cos(pose.z()), s = std::sin(pose.z());
    pose.x() += (twist.x() * c - twist.y() * s) * dt;
    pose.y() += (twist.x() * s + twist.y() * c) * dt;
    pose.z() += twist.z() * dt;
  };
  for (int k = 1; k <= 18000; ++k) {
    const double t = k * kDt;
    const Eigen::Vector3d v = true_twist(t - kDt);
    integrate(truth, v, kDt);
    GyroRate g;
    g.stamp = t;
    g.yaw_rate = v.z() + gyro_bias + gyro_sigma * n01(rng);
    g.variance = gyro_sigma * gyro_sigma;
    filter.update(g);
    if (k % 2 == 0) {
      // Wheel noise grows with speed (slip); the reported covariance says so.
      const Eigen::Vector3d sigma(0.002 + 0.03 * std::abs(v.x()), 0.002 + 0.03 * std::abs(v.y()),
                                  0.002 + 0.1 * std::abs(v.z()));
      WheelTwist w;
      w.stamp = t;
      w.twist = Eigen::Vector3d(v.x() * (1 + kScale), v.y() * (1 + kScale), v.z() * (1 + kSlip)) +
                Eigen::Vector3d(sigma.x() * n01(rng), sigma.y() * n01(rng), sigma.z() * n01(rng));
      w.covariance = sigma.cwiseAbs2().asDiagonal();
      integrate(wheel_only, w.twist, 2 * kDt);
      filter.update(w);
    }
    const FilteredOdometry e = filter.estimate();
    r.filter_yaw_error_max =
        std::max(r.filter_yaw_error_max, std::abs(wrap(e.pose.z() - truth.z())));
    r.wheel_yaw_error_max =
        std::max(r.wheel_yaw_error_max, std::abs(wrap(wheel_only.z() - truth.z())));
  }
  const FilteredOdometry e = filter.estimate();
  r.filter_yaw_error_end = std::abs(wrap(e.pose.z() - truth.z()));
  r.wheel_yaw_error_end = std::abs(wrap(wheel_only.z() - truth.z()));
  r.filter_position_error_end = (e.pose.head<2>() - truth.head<2>()).norm();
  r.wheel_position_error_end = (wheel_only.head<2>() - truth.head<2>()).norm();
  r.bias_error_end = std::abs(e.gyro_bias - gyro_bias);
  r.bias_sigma_end = e.gyro_bias_sigma;
  return r;
}

TEST(OdometryFilter, HeadingBeatsWheelOdometryOnASkiddingDrive) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const DriveResult r = simulate_drive(seed);
    SCOPED_TRACE("seed " + std::to_string(seed));
    // Wheel-only: 8 % of the ~ 14 rad turned ends ~ 1.1 rad off.
    EXPECT_GT(r.wheel_yaw_error_end, 1.0);
    EXPECT_LT(r.filter_yaw_error_max, 0.15 * r.wheel_yaw_error_max);
    EXPECT_LT(r.filter_yaw_error_end, 0.15 * r.wheel_yaw_error_end);
    EXPECT_LT(r.filter_position_error_end, r.wheel_position_error_end);
    // The bias is learnt (standstill and straight runs), within a few sigma.
    EXPECT_LT(r.bias_error_end, 0.002);
    EXPECT_LT(r.bias_sigma_end, 0.005);
  }
}

TEST(OdometryFilter, CovarianceGrowsWithoutMeasurements) {
  OdometryFilter filter;
  filter.reset(0.0, Eigen::Vector3d(1.0, 2.0, 0.5));
  for (int k = 1; k <= 100; ++k) {
    filter.update(
        WheelTwist{k * 0.01, Eigen::Vector3d(0.5, 0.0, 0.1), Eigen::Matrix3d::Identity() * 1e-4});
  }
  FilteredOdometry previous = filter.estimate();
  for (int k = 1; k <= 20; ++k) {
    filter.predict(1.0 + 0.1 * k);
    const FilteredOdometry now = filter.estimate();
    EXPECT_GT(now.pose_covariance(0, 0) + now.pose_covariance(1, 1),
              previous.pose_covariance(0, 0) + previous.pose_covariance(1, 1));
    EXPECT_GT(now.pose_covariance(2, 2), previous.pose_covariance(2, 2));
    EXPECT_GT(now.twist_covariance(0, 0), previous.twist_covariance(0, 0));
    // The pose keeps moving with the last twist.
    EXPECT_GT((now.pose.head<2>() - previous.pose.head<2>()).norm(), 0.04);
    previous = now;
  }
  EXPECT_NEAR(previous.stamp, 3.0, 1e-9);
}

TEST(OdometryFilter, RefusesBadMeasurementsAndKeepsItsState) {
  OdometryFilter filter;
  filter.reset(0.0);
  for (int k = 1; k <= 50; ++k) {
    filter.update(
        WheelTwist{k * 0.01, Eigen::Vector3d(0.3, 0.0, 0.0), Eigen::Matrix3d::Identity() * 1e-4});
  }
  const FilteredOdometry before = filter.estimate();
  auto expect_refused = [&](auto&& call, const std::string& what) {
    try {
      call();
      ADD_FAILURE() << "accepted: " << what;
    } catch (const OdometryFilterError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
    const FilteredOdometry after = filter.estimate();
    EXPECT_EQ(after.stamp, before.stamp);
    EXPECT_EQ(after.pose, before.pose);
    EXPECT_EQ(after.twist, before.twist);
    EXPECT_EQ(after.pose_covariance, before.pose_covariance);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_refused(
      [&] {
        filter.update(WheelTwist{0.6, {nan, 0, 0}, Eigen::Matrix3d::Identity()});
      },
      "wheel twist[0] is not finite");
  Eigen::Matrix3d bad_cov = Eigen::Matrix3d::Identity();
  bad_cov(2, 2) = -1.0;
  expect_refused(
      [&] {
        filter.update(WheelTwist{0.6, {0.3, 0, 0}, bad_cov});
      },
      "wheel twist covariance(2,2)");
  expect_refused(
      [&] {
        filter.update(GyroRate{0.6, std::numeric_limits<double>::infinity(), 1e-5});
      },
      "gyro yaw rate is not finite");
  expect_refused([&] { filter.update(GyroRate{nan, 0.0, 1e-5}); }, "gyro stamp is not finite");
  expect_refused([&] { filter.update(GyroRate{0.1, 0.0, 1e-5}); }, "older than the filter's time");
  // A late sample is told apart from a malformed one: the caller drops it and counts it.
  EXPECT_THROW(filter.update(GyroRate{0.1, 0.0, 1e-5}), LateMeasurement);
  EXPECT_THROW(filter.update(WheelTwist{0.1, {0.3, 0, 0}, Eigen::Matrix3d::Identity() * 1e-4}), LateMeasurement);
  try {
    filter.update(GyroRate{nan, 0.0, 1e-5});
  } catch (const LateMeasurement&) {
    ADD_FAILURE() << "a NaN stamp is bad input, not a late sample";
  } catch (const OdometryFilterError&) {
  }
  // The filter still works afterwards.
  filter.update(WheelTwist{0.6, {0.3, 0, 0}, Eigen::Matrix3d::Identity() * 1e-4});
  EXPECT_GT(filter.estimate().pose.x(), before.pose.x());
}

TEST(OdometryFilter, RefusesBadParameters) {
  OdometryFilterParams p;
  p.max_step = 0.0;
  EXPECT_THROW(OdometryFilter{p}, OdometryFilterError);
}

}  // namespace
}  // namespace concert::nav
