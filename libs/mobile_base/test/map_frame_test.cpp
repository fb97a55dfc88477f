// MapFrame: the odometry frame in the map from a localisation and the robot's odometry at the
// localisation's stamp.
#include "concert/mobile_base/map_frame.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace concert::mobile_base {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(MapFrame, IsTheIdentityUntilALocalisationMatchesAnOdometryStamp) {
  MapFrame f;
  EXPECT_FALSE(f.localised());
  EXPECT_TRUE(f.map_T_odom().isZero());
  // No odometry yet: a localisation cannot be placed.
  EXPECT_FALSE(f.on_localisation(100 * kMs, {1, 2, 0.3}));
  f.on_odometry(100 * kMs, {0, 0, 0});
  // A stamp far from every odometry sample is not matched either.
  EXPECT_FALSE(f.on_localisation(500 * kMs, {1, 2, 0.3}));
  EXPECT_FALSE(f.localised());
  EXPECT_TRUE(f.on_localisation(110 * kMs, {1, 2, 0.3}));
  EXPECT_TRUE(f.localised());
  EXPECT_TRUE(f.map_T_odom().isApprox(Eigen::Vector3d(1, 2, 0.3)));
}

TEST(MapFrame, PutsAMapPointWhereTheRobotsOdometryFindsIt) {
  // The robot switched on in a building at (6.0, 1.2) facing north: its odometry starts at 0.
  // It drives 4 m (the odometry's yaw drifts by 2 degrees on the way); nav then localises the
  // base in the map at the stamp of one odometry sample.
  const Eigen::Vector3d start(6.0, 1.2, M_PI / 2);
  MapFrame f;
  Eigen::Vector3d truth = start;
  Eigen::Vector3d odom = Eigen::Vector3d::Zero();
  const double drift = 2.0 * M_PI / 180.0 / 400.0;
  for (int i = 1; i <= 400; ++i) {
    const Eigen::Vector3d step(0.01, 0.0, (i < 200 ? 0.0 : M_PI / 2 / 200.0));
    truth = compose(truth, step);
    odom = compose(odom, Eigen::Vector3d(step.x(), step.y(), step.z() + drift));
    f.on_odometry(i * 10 * kMs, odom);
  }
  // The localisation carries the true pose at the stamp of sample 400 (and a later, unmatched
  // stamp changes nothing).
  ASSERT_TRUE(f.on_localisation(4000 * kMs, truth));
  EXPECT_FALSE(f.on_localisation(9000 * kMs, Eigen::Vector3d::Zero()));
  // A point 1 m ahead of the base in the map is, in the odometry frame, 1 m ahead of the
  // odometry's base pose.
  const Eigen::Isometry3d base_map = isometry(truth);
  const Eigen::Vector3d ahead_map = base_map * Eigen::Vector3d(1.0, 0.0, 1.2);
  Eigen::Isometry3d area = Eigen::Isometry3d::Identity();
  area.translation() = ahead_map;
  const Eigen::Vector3d ahead_odom = isometry(odom) * Eigen::Vector3d(1.0, 0.0, 1.2);
  EXPECT_LT((f.to_odom(area).translation() - ahead_odom).norm(), 1e-9);
  EXPECT_LT((f.to_map(f.to_odom(area)).translation() - ahead_map).norm(), 1e-9);
  // The odometry frame's origin lies near the start (the drift moves it a little).
  EXPECT_LT((f.map_T_odom().head<2>() - start.head<2>()).norm(), 0.2);
}

TEST(MapFrame, ComposeAndInverseAreConsistent) {
  const Eigen::Vector3d a(1.0, -2.0, 2.9), b(0.3, 0.4, 0.5);
  EXPECT_TRUE(compose(a, inverse(a)).isZero(1e-12));
  const Eigen::Vector3d ab = compose(a, b);
  EXPECT_TRUE((isometry(a) * isometry(b)).isApprox(isometry(ab), 1e-12));
  EXPECT_NEAR(ab.z(), std::atan2(std::sin(3.4), std::cos(3.4)), 1e-12);  // wrapped
}

}  // namespace
}  // namespace concert::mobile_base
