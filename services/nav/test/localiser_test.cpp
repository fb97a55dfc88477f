// The localiser on a synthetic storey: ray casting and the distance field, a > 30 m seeded route
// through a door (mean error <= 5 cm), unmapped boxes, a kidnapped robot, bad input.
#include "nav/localiser.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "localiser_sim.hpp"

namespace concert::nav {
namespace {

using ::testing::HasSubstr;
using testing::Rect;

std::shared_ptr<const LikelihoodField> storey_field() {
  static const auto field = std::make_shared<const LikelihoodField>(
      testing::rasterise(testing::storey_walls(), 0.05, {0.021, 0.037}));
  return field;
}

const bim::OccupancyGrid& world(bool with_boxes) {
  static const bim::OccupancyGrid empty = testing::rasterise(testing::storey_walls(), 0.01);
  static const bim::OccupancyGrid boxed = [] {
    std::vector<Rect> all = testing::storey_walls();
    for (const Rect& r : testing::unmapped_boxes()) all.push_back(r);
    return testing::rasterise(all, 0.01);
  }();
  return with_boxes ? boxed : empty;
}

TEST(CastRay, StopsAtTheFirstOccupiedCellBoundary) {
  bim::OccupancyGrid g = bim::OccupancyGrid::filled(20, 10, 0.1, {0.0, 0.0});
  for (int row = 0; row < 10; ++row)
    g.at(15, row) = bim::OccupancyGrid::kOccupied;  // x in [1.5, 1.6]
  EXPECT_NEAR(cast_ray(g, {0.25, 0.45}, 0.0, 10.0), 1.25, 1e-9);
  // At 60 degrees the ray leaves through the grid's top edge (y = 1.0; outside counts as
  // occupied) before it reaches the wall.
  EXPECT_NEAR(cast_ray(g, {0.25, 0.45}, std::numbers::pi / 3, 10.0),
              0.55 / std::sin(std::numbers::pi / 3), 1e-9);
  EXPECT_NEAR(cast_ray(g, {0.25, 0.45}, 0.0, 1.0), 1.0, 1e-12);                // max range
  EXPECT_NEAR(cast_ray(g, {0.25, 0.45}, std::numbers::pi, 10.0), 0.25, 1e-9);  // grid edge
  EXPECT_EQ(cast_ray(g, {1.55, 0.45}, 0.0, 10.0), 0.0);                        // inside a wall
}

TEST(LikelihoodField, DistancesToTheNearestWallFace) {
  bim::OccupancyGrid g = bim::OccupancyGrid::filled(40, 40, 0.05, {0.0, 0.0});
  for (int row = 0; row < 40; ++row)
    g.at(20, row) = bim::OccupancyGrid::kOccupied;  // x in [1.0, 1.05]
  const LikelihoodField field(g, 1.0);
  Eigen::Vector2d grad;
  EXPECT_NEAR(field.distance({0.6, 1.0}, grad), 0.4, 1e-6);  // 0.4 m in front of the face x = 1.0
  EXPECT_NEAR(grad.x(), -1.0, 1e-6);
  EXPECT_NEAR(grad.y(), 0.0, 1e-6);
  EXPECT_NEAR(field.distance({1.35, 1.0}), 0.3, 1e-6);  // behind the face x = 1.05
  EXPECT_EQ(field.distance({1.02, 1.0}), 0.0);          // in the wall
  EXPECT_NEAR(field.distance({0.1, 1.0}), 0.9, 1e-6);
  EXPECT_EQ(field.distance({-5.0, 1.0}), 1.0);  // outside: max distance
  EXPECT_THROW(LikelihoodField(bim::OccupancyGrid::filled(5, 5, 0.05, {0, 0})), LocaliserError);
}

struct RouteResult {
  double mean_error{0.0};
  double max_error{0.0};
  double max_yaw_error{0.0};
  double length{0.0};
  int refined{0};
  int tracking{0};
  int scans{0};
};

RouteResult run_route(bool boxes, std::uint64_t seed) {
  const std::vector<Eigen::Vector3d> truth = testing::route();
  std::mt19937_64 rng(seed);
  const std::vector<Eigen::Vector3d> odom =
      testing::drifting_odometry(truth, rng, {3.0, -2.0, 0.7});
  LocaliserParams params;
  params.seed = seed;
  Localiser localiser(storey_field(), params);
  // The user's initial pose is 20 cm and 3 degrees off.
  localiser.set_pose(truth[0] + Eigen::Vector3d(0.15, -0.13, 0.05), {0.2, 0.2, 0.1}, odom[0]);
  RouteResult r;
  r.length = testing::route_length(truth);
  double sum = 0.0;
  int counted = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const LocaliserEstimate& e =
        localiser.update(odom[i], testing::simulate_scan(world(boxes), truth[i], rng));
    ++r.scans;
    r.refined += e.refined ? 1 : 0;
    r.tracking += e.status == LocaliserStatus::kTracking ? 1 : 0;
    if (i < 10) continue;  // the first second: converging from the user's guess
    const Eigen::Vector2d err = testing::pose_error(e.pose, truth[i]);
    sum += err.x();
    ++counted;
    r.max_error = std::max(r.max_error, err.x());
    r.max_yaw_error = std::max(r.max_yaw_error, err.y());
  }
  r.mean_error = sum / counted;
  return r;
}

TEST(Localiser, FollowsAThirtyMetreRouteThroughADoorWithinFiveCentimetres) {
  const RouteResult r = run_route(false, 7);
  RecordProperty("mean_error_m", std::to_string(r.mean_error));
  RecordProperty("max_error_m", std::to_string(r.max_error));
  EXPECT_GE(r.length, 30.0);
  EXPECT_LE(r.mean_error, 0.05);
  EXPECT_LE(r.max_error, 0.25);
  EXPECT_LE(r.max_yaw_error, 0.05);
  EXPECT_EQ(r.tracking, r.scans);
  EXPECT_GT(r.refined, r.scans * 9 / 10);
}

TEST(Localiser, ToleratesBoxesThatAreNotInTheMap) {
  const RouteResult r = run_route(true, 11);
  RecordProperty("mean_error_m", std::to_string(r.mean_error));
  EXPECT_LE(r.mean_error, 0.05);
  EXPECT_LE(r.max_error, 0.25);
  EXPECT_EQ(r.tracking, r.scans);
}

TEST(Localiser, AKidnappedRobotIsReportedLostAndRecovers) {
  const std::vector<Eigen::Vector3d> truth = testing::route();
  std::mt19937_64 rng(5);
  const std::vector<Eigen::Vector3d> odom = testing::drifting_odometry(truth, rng);
  Localiser localiser(storey_field());
  localiser.set_pose(truth[0], {0.1, 0.1, 0.05}, odom[0]);
  // Tracked for 10 s; then the robot is carried into the other room (the odometry sees nothing):
  // from then on it drives the second half of the route while the filter believes the first.
  const std::size_t kidnap = 100;
  const std::size_t offset = truth.size() / 2;
  ASSERT_GT(truth.size(), offset + kidnap + 200);
  int lost_at = -1, recovered_at = -1;
  double final_error = 0.0;
  for (std::size_t i = 0; i + offset < truth.size(); ++i) {
    const Eigen::Vector3d& where = i < kidnap ? truth[i] : truth[i + offset];
    const LocaliserEstimate& e = localiser.update(
        i < kidnap ? odom[i]
                   : testing::compose(odom[kidnap],
                                      testing::compose(testing::inverse(odom[kidnap + offset]),
                                                       odom[i + offset])),
        testing::simulate_scan(world(false), where, rng));
    if (i < kidnap) {
      ASSERT_EQ(e.status, LocaliserStatus::kTracking) << "scan " << i;
      continue;
    }
    if (lost_at < 0 && e.status == LocaliserStatus::kLost) lost_at = static_cast<int>(i);
    if (lost_at >= 0 && recovered_at < 0 && e.status == LocaliserStatus::kTracking) {
      recovered_at = static_cast<int>(i);
    }
    final_error = testing::pose_error(e.pose, where).x();
  }
  RecordProperty("scans_to_lost", lost_at - static_cast<int>(kidnap));
  RecordProperty("scans_to_recovered", recovered_at - static_cast<int>(kidnap));
  ASSERT_GE(lost_at, 0) << "the kidnapping was not noticed";
  EXPECT_LE(lost_at - static_cast<int>(kidnap), 3 * LocaliserParams{}.lost_after);
  ASSERT_GE(recovered_at, 0) << "never recovered";
  EXPECT_LE(final_error, 0.1);
}

TEST(Localiser, WithoutAnInitialPoseItLocalisesGlobally) {
  const std::vector<Eigen::Vector3d> truth = testing::route();
  std::mt19937_64 rng(3);
  const std::vector<Eigen::Vector3d> odom = testing::drifting_odometry(truth, rng);
  Localiser localiser(storey_field());
  EXPECT_EQ(localiser.estimate().status, LocaliserStatus::kUninitialised);
  LocaliserEstimate e =
      localiser.update(odom[0], testing::simulate_scan(world(false), truth[0], rng));
  EXPECT_EQ(e.status, LocaliserStatus::kLost);
  std::size_t i = 1;
  for (; i < 300 && e.status != LocaliserStatus::kTracking; ++i) {
    e = localiser.update(odom[i], testing::simulate_scan(world(false), truth[i], rng));
  }
  ASSERT_EQ(e.status, LocaliserStatus::kTracking);
  EXPECT_LE(testing::pose_error(e.pose, truth[i - 1]).x(), 0.1);
}

TEST(Localiser, RefusesBadInputAndKeepsItsEstimate) {
  Localiser localiser(storey_field());
  std::mt19937_64 rng(1);
  const Eigen::Vector3d truth(1.5, 1.5, 0.0);
  localiser.set_pose(truth, {0.05, 0.05, 0.02}, Eigen::Vector3d::Zero());
  const LocaliserEstimate before =
      localiser.update(Eigen::Vector3d::Zero(), testing::simulate_scan(world(false), truth, rng));
  PlanarScan scan = testing::simulate_scan(world(false), truth, rng);
  auto expect_refused = [&](const Eigen::Vector3d& odom, const PlanarScan& s,
                            const std::string& what) {
    try {
      localiser.update(odom, s);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const LocaliserError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
    EXPECT_EQ(localiser.estimate().pose, before.pose);
    EXPECT_EQ(localiser.estimate().status, before.status);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_refused({nan, 0, 0}, scan, "odometry pose is not finite");
  PlanarScan short_scan = scan;
  short_scan.ranges.pop_back();
  expect_refused(Eigen::Vector3d::Zero(), short_scan, "720 angles but 719 ranges");
  PlanarScan bad_angle = scan;
  bad_angle.angles[3] = nan;
  expect_refused(Eigen::Vector3d::Zero(), bad_angle, "scan angle 3 is not finite");
  // NaN ranges are no returns, not errors.
  PlanarScan nan_ranges = scan;
  for (std::size_t k = 0; k < nan_ranges.ranges.size(); k += 2) nan_ranges.ranges[k] = nan;
  EXPECT_NO_THROW(localiser.update(Eigen::Vector3d::Zero(), nan_ranges));
  EXPECT_LE(testing::pose_error(localiser.estimate().pose, truth).x(), 0.05);
  LocaliserParams p;
  p.particles = 0;
  EXPECT_THROW(Localiser(storey_field(), p), LocaliserError);
  EXPECT_THROW(Localiser(nullptr), LocaliserError);
}

}  // namespace
}  // namespace concert::nav
