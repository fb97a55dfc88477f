// The follow-me MPC (eq. 4, 5) on Ipopt and the obstacle grid: a straight pull follows the
// person; a straight pull toward a pillar stops short of it (the soft minimum distance holds);
// warm starts; bad input and bad parameters are refused with the reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>
#include <numeric>

#include "collab/follow_me_mpc.hpp"
#include "collab/obstacle_map.hpp"
#include "example_arm.hpp"

namespace concert::collab {
namespace {

using test::ExampleArm;

std::vector<RobotSphere> spheres() { return perimeter_spheres(1.0, 0.7); }

TEST(FollowMeMpc, FollowsAStraightPull) {
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  const auto run = test::pull(mpc, spheres(), {}, 6.0);
  EXPECT_EQ(run.failures, 0);
  // The hand walks 3.6 m at 0.6 m/s; the base follows most of the way.
  EXPECT_GT(run.base_travel, 2.5);
  EXPECT_LT(run.mean_lag, 1.0);
  EXPECT_GT(run.warm, 100);
}

TEST(FollowMeMpc, KeepsTheMinimumDistanceToAPillarOnAStraightPull) {
  // The person walks straight through a pillar 3 m ahead of the base; the robot must stop short.
  const std::vector<test::Pillar> pillars{{Eigen::Vector2d(3.0, 0.0), 0.3}};
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  const auto run = test::pull(mpc, spheres(), pillars, 10.0);
  // Head-on, the solver may hit its iteration limit while choosing a side: the controller then
  // stops the base for that cycle (counted as a failure here); a few such cycles are allowed.
  EXPECT_LE(run.failures, 4) << "of 200 cycles";
  EXPECT_GE(run.min_clearance, 0.0) << "the robot touched the pillar";
  // It did follow up to the pillar (not stuck at the start).
  EXPECT_LT(run.min_clearance, 0.4);
  EXPECT_GT(run.base_travel, 1.0);
}

TEST(FollowMeMpc, WithoutTheObstacleTermTheSamePullHitsThePillar) {
  // The counter-test: the pillar unseen (no obstacles fed), the robot drives into it.
  const std::vector<test::Pillar> none;
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  const auto run = test::pull(mpc, spheres(), none, 10.0);
  // Base spheres reach x = 3 - 0.3 with the front sphere (offset 0.25, r 0.43) when travel > 2.0.
  EXPECT_GT(run.base_travel, 2.1);
}

TEST(FollowMeMpc, WarmStartsNeedFewerIterations) {
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  const auto run = test::pull(mpc, spheres(), {{Eigen::Vector2d(3.0, 0.5), 0.3}}, 4.0);
  ASSERT_GT(run.iterations.size(), 20u);
  const int cold = run.iterations.front();
  std::vector<int> warm(run.iterations.begin() + 1, run.iterations.end());
  std::nth_element(warm.begin(), warm.begin() + static_cast<long>(warm.size() / 2), warm.end());
  EXPECT_LT(warm[warm.size() / 2], cold);
}

// The example arm standing at its posture, the base at the origin, no force.
MpcInput at_posture() {
  const ExampleArm arm;
  MpcInput in;
  in.q = ExampleArm::posture();
  in.ee_in_base = arm.fk(in.q);
  in.arm_jacobian = arm.jacobian(in.q);
  return in;
}

TEST(FollowMeMpc, NoForceNoMotion) {
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  MpcInput in = at_posture();
  const auto r = mpc.solve(in);
  ASSERT_TRUE(r.ok) << r.status;
  EXPECT_LT(r.base_velocity.norm(), 1e-3);
  EXPECT_LT(r.joint_velocity.norm(), 1e-3);
}

// A hard pull from rest: the base's first velocity is bounded by its acceleration bound
// (base_lin_acc_max 2 m/s^2 over a 0.1 s step: 0.2 m/s) times the share the drives sustain
// (model::DriveBudget in the adapter), never below min_base_acceleration_scale (0.1) so the base
// can still brake. A share outside [0, 1] is refused.
TEST(FollowMeMpc, TheBaseAcceleratesNoHarderThanTheDrivesSustain) {
  std::vector<double> vx;
  for (const double scale : {1.0, 0.25, 0.0}) {
    FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
    MpcInput in = at_posture();
    in.force = Eigen::Vector3d(200.0, 0.0, 0.0);
    in.base_acceleration_scale = scale;
    const auto r = mpc.solve(in);
    ASSERT_TRUE(r.ok) << r.status;
    EXPECT_LE(std::abs(r.base_velocity.x()), std::max(0.1, scale) * 2.0 * 0.1 + 1e-6) << "scale " << scale;
    vx.push_back(std::abs(r.base_velocity.x()));
  }
  EXPECT_GT(vx[0], 0.25 * 0.2 + 0.01) << "the pull does not reach the bound: the test shows nothing";
  EXPECT_GT(vx[1], vx[2]);
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  MpcInput in = at_posture();
  in.base_acceleration_scale = 1.5;
  const auto r = mpc.solve(in);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.status.find("acceleration scale"), std::string::npos) << r.status;
}

TEST(FollowMeMpc, BadInputIsRefusedWithTheReason) {
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  MpcInput in;
  in.q = Eigen::VectorXd::Zero(6);
  in.arm_jacobian = Eigen::MatrixXd::Zero(3, 6);
  auto r = mpc.solve(in);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.status.find("expected 7"), std::string::npos) << r.status;
  in.q = Eigen::VectorXd::Zero(7);
  in.arm_jacobian = Eigen::MatrixXd::Zero(3, 7);
  in.force.x() = std::nan("");
  r = mpc.solve(in);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.status.find("NaN"), std::string::npos) << r.status;
  in.force.x() = 0;
  in.period = -0.02;
  r = mpc.solve(in);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.status.find("period"), std::string::npos) << r.status;
  in.period = 0.0;
  in.obstacles.assign(9, Sphere{});
  r = mpc.solve(in);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.status.find("at most 8"), std::string::npos) << r.status;
}

// Eq. 4's mass-damper advances by the control period, not by an MPC step: 10 solves at 50 Hz under
// a constant 40 N are 0.2 s of M v' + D v = F (M 8 kg, D 40 N s/m): v = 1 - 0.9^10 = 0.651 m/s with
// the semi-implicit step (analytically 1 - e^-1 = 0.632); one MPC step a solve would give 1 s
// (0.99 m/s).
TEST(FollowMeMpc, TheVirtualMassDamperRunsInTheControlPeriod) {
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  MpcInput in = at_posture();
  in.force = Eigen::Vector3d(40.0, 0.0, 0.0);
  in.period = 0.02;
  MpcResult r;
  for (int i = 0; i < 10; ++i) {
    r = mpc.solve(in);
    ASSERT_TRUE(r.ok) << r.status;
  }
  EXPECT_NEAR(r.virtual_velocity.x(), 1.0 - std::pow(0.9, 10), 1e-6);
  EXPECT_GT(r.base_velocity.x(), 0.05);  // and the base moves along the pull
}

// The force is low-passed before eq. 4 (params.force_filter): the first solve takes it as it is,
// then a step from 0 to 40 N rises with the filter's time constant, period / (tau + period) per
// solve; with no filter it passes straight through.
TEST(FollowMeMpc, TheForceIsLowPassed) {
  MpcParams p;
  p.force_filter = 0.15;
  FollowMeMpc mpc(p, ExampleArm::limits(), spheres());
  MpcInput in = at_posture();
  in.period = 0.02;
  auto r = mpc.solve(in);
  ASSERT_TRUE(r.ok) << r.status;
  EXPECT_EQ(r.force.x(), 0.0);
  in.force = Eigen::Vector3d(40.0, 0.0, 0.0);
  const double a = 0.02 / (0.15 + 0.02);
  double expected = 0.0;
  for (int i = 0; i < 5; ++i) {
    r = mpc.solve(in);
    ASSERT_TRUE(r.ok) << r.status;
    expected += a * (40.0 - expected);
    EXPECT_NEAR(r.force.x(), expected, 1e-9) << "solve " << i;
  }
  EXPECT_LT(r.force.x(), 0.6 * 40.0);  // five periods (0.1 s) into a 0.15 s filter
  mpc.reset();  // forgets the filtered force too
  r = mpc.solve(in);
  EXPECT_NEAR(r.force.x(), 40.0, 1e-9);
  p.force_filter = 0.0;
  FollowMeMpc raw(p, ExampleArm::limits(), spheres());
  in.force.setZero();
  ASSERT_TRUE(raw.solve(in).ok);
  in.force = Eigen::Vector3d(40.0, 0.0, 0.0);
  EXPECT_NEAR(raw.solve(in).force.x(), 40.0, 1e-9);
}

// An obstacle keeps its constraint slot (and its slack's and multiplier's warm start) when the
// grid hands the obstacles over in another order: the same second solve with the obstacles
// swapped gives the same answer, to the last bit. With slot_match 0 (the order as given) the
// warm start belongs to the other obstacle and the answer differs.
TEST(FollowMeMpc, ObstaclesKeepTheirSlotsWhenTheirOrderChanges) {
  const Sphere a{Eigen::Vector3d(1.6, 0.55, 0.0), 0.2};
  const Sphere b{Eigen::Vector3d(1.4, -0.6, 0.0), 0.2};
  auto second = [&](double slot_match, bool swap) {
    MpcParams p;
    p.slot_match = slot_match;
    FollowMeMpc mpc(p, ExampleArm::limits(), spheres());
    MpcInput in = at_posture();
    in.force = Eigen::Vector3d(60.0, 0.0, 0.0);
    in.period = 0.02;
    in.obstacles = {a, b};
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(mpc.solve(in).ok);
    if (swap) in.obstacles = {b, a};
    return mpc.solve(in);
  };
  const MpcResult same = second(0.3, false), swapped = second(0.3, true);
  ASSERT_TRUE(same.ok && swapped.ok) << same.status << " / " << swapped.status;
  EXPECT_EQ(same.iterations, swapped.iterations);
  EXPECT_EQ(same.base_velocity, swapped.base_velocity);
  EXPECT_EQ(same.joint_velocity, swapped.joint_velocity);
  const MpcResult same0 = second(0.0, false), swapped0 = second(0.0, true);
  ASSERT_TRUE(same0.ok && swapped0.ok) << same0.status << " / " << swapped0.status;
  EXPECT_NE(same0.base_velocity, swapped0.base_velocity);
}

TEST(FollowMeMpc, SetPostureChecksSizeAndLimits) {
  FollowMeMpc mpc(MpcParams{}, ExampleArm::limits(), spheres());
  EXPECT_THROW(mpc.set_posture(Eigen::VectorXd::Zero(6)), std::invalid_argument);
  Eigen::VectorXd q = ExampleArm::posture();
  q[2] = ExampleArm::limits().q_max[2] + 0.1;
  try {
    mpc.set_posture(q);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 2"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(mpc.set_posture(ExampleArm::posture()));
}

TEST(FollowMeMpc, BadParametersThrowNamingThem) {
  auto limits = ExampleArm::limits();
  MpcParams p;
  p.dt = 0;
  EXPECT_THROW(FollowMeMpc(p, limits, spheres()), std::invalid_argument);
  limits.qd_max[3] = 0;
  try {
    FollowMeMpc m(MpcParams{}, limits, spheres());
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(FollowMeMpc(MpcParams{}, ExampleArm::limits(), {}), std::invalid_argument);
  MpcParams f;
  f.force_filter = -0.1;
  try {
    FollowMeMpc m(f, ExampleArm::limits(), spheres());
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("force_filter"), std::string::npos) << e.what();
  }
}

TEST(ObstacleGrid, NearestCellPerSector) {
  GridParams gp;
  gp.sectors = 4;
  ObstacleGrid g(gp);
  g.reset(Eigen::Vector2d(1.0, 1.0));
  g.add_point({2.0, 1.05});   // sector 0 (east), 1 m
  g.add_point({3.0, 1.05});   // sector 0, 2 m: not active
  g.add_point({0.95, 2.55});  // sector 1 (north, just past 90 deg), 1.5 m
  g.add_point({-0.5, 0.9});   // sector 2 (west), 1.5 m
  g.add_point({9.0, 9.0});    // outside the map
  EXPECT_EQ(g.occupied(), 4u);
  const auto a = g.active({1.0, 1.0});
  ASSERT_EQ(a.size(), 3u);
  EXPECT_NEAR(a[0].centre.x(), 2.05, 1e-9);
  EXPECT_NEAR(a[0].centre.y(), 1.05, 1e-9);
  EXPECT_NEAR(a[0].radius, 0.1 * std::sqrt(2.0) / 2, 1e-9);
}

TEST(ObstacleGrid, SonarArcAndRanges) {
  ObstacleGrid g(GridParams{});
  g.reset(Eigen::Vector2d::Zero());
  SonarReading s;
  s.position = {0.3, 0.0};
  s.heading = 0.0;
  s.range = 1.0;
  g.add_sonar(s);
  EXPECT_GE(g.occupied(), 3u);  // the arc spans several cells
  for (const auto& c : g.cells()) EXPECT_NEAR((c.centre.head<2>() - s.position).norm(), 1.0, 0.1);
  ObstacleGrid h(GridParams{});
  h.reset(Eigen::Vector2d::Zero());
  s.range = 2.5;  // beyond the sonar's range: nothing seen
  h.add_sonar(s);
  EXPECT_EQ(h.occupied(), 0u);
  EXPECT_THROW(ObstacleGrid(GridParams{.resolution = 0.0}), std::invalid_argument);
}


// A planar scan from a lidar turned and placed in the world: returns land where the beam met
// something, and what is out of range or not finite adds nothing.
TEST(ObstacleGrid, ScanReturnsLandInTheWorldFromTheSensorsPose) {
  ObstacleGrid g(GridParams{});
  g.reset(Eigen::Vector2d(1.0, 0.0));
  PlanarScanReading scan;
  scan.world_T_sensor = Eigen::Translation3d(1.0, 0.0, 0.3) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  scan.angle_min = -M_PI / 2;
  scan.angle_increment = M_PI / 2;
  scan.range_min = 0.1;
  scan.range_max = 5.0;
  // Beams at -90, 0, +90 degrees of the sensor (world east, north, west) and two more.
  scan.ranges = {1.0, 2.0, std::numeric_limits<double>::infinity(), 0.05, 7.0};
  g.add_scan(scan);
  ASSERT_EQ(g.occupied(), 2u);
  std::vector<Eigen::Vector2d> seen;
  for (const auto& c : g.cells()) seen.push_back(c.centre.head<2>());
  auto near = [&](const Eigen::Vector2d& p) {
    return std::any_of(seen.begin(), seen.end(), [&](const Eigen::Vector2d& c) { return (c - p).norm() < 0.08; });
  };
  EXPECT_TRUE(near({2.0, 0.0}));  // 1 m east of the sensor
  EXPECT_TRUE(near({1.0, 2.0}));  // 2 m north
}

TEST(ObstacleGrid, ASonarReadsAlongItsXAxis) {
  const Eigen::Isometry3d T = Eigen::Translation3d(0.5, -0.2, 0.4) * Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ());
  const SonarReading r = sonar_reading(T, 1.2, 2.0, 0.5);
  EXPECT_NEAR(r.position.x(), 0.5, 1e-12);
  EXPECT_NEAR(r.position.y(), -0.2, 1e-12);
  EXPECT_NEAR(r.heading, -M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(r.range, 1.2);
  EXPECT_DOUBLE_EQ(r.half_angle, 0.25);
  EXPECT_LT(sonar_reading(T, std::numeric_limits<double>::quiet_NaN(), 2.0, 0.5).range, 0.0);
}

// The position command follows the MPC's velocities but never runs more than the wind-up bound
// ahead of a held-back arm, nor past a joint limit.
TEST(FollowCommand, IntegratesWithinTheWindUpBoundAndTheLimits) {
  ArmLimits limits;
  limits.q_min = Eigen::Vector2d(-1.0, -1.0);
  limits.q_max = Eigen::Vector2d(1.0, 0.35);
  const Eigen::Vector2d q(0.0, 0.3);    // the arm held where it is
  const Eigen::Vector2d qd(0.5, 0.5);   // the MPC asks to move on
  Eigen::VectorXd cmd;                  // no command yet: starts at q
  integrate_position_command(cmd, q, qd, 0.02, 0.1, limits);
  EXPECT_NEAR(cmd[0], 0.01, 1e-12);
  EXPECT_NEAR(cmd[1], 0.31, 1e-12);
  for (int k = 0; k < 50; ++k) integrate_position_command(cmd, q, qd, 0.02, 0.1, limits);
  EXPECT_NEAR(cmd[0], 0.1, 1e-12);   // wind-up bound
  EXPECT_NEAR(cmd[1], 0.35, 1e-12);  // the joint limit
  const Eigen::Vector3d f = planar_world_force(Eigen::Vector3d(10.0, 0.0, -30.0), M_PI / 2);
  EXPECT_NEAR(f.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.y(), 10.0, 1e-12);
  EXPECT_EQ(f.z(), 0.0);
}

}  // namespace
}  // namespace concert::collab
