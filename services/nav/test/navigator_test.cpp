// The navigator as a whole, without DDS: the demo robot's model (omni-steering base, lidars),
// a two-room map with a door, scans ray-cast in the true map, and the commanded twist integrated
// as the base moves (wheel odometry with slip). It must localise, plan through the door, drive
// there and stop within the tolerances, measured against the truth; and refuse what it cannot do
// with a reason.
#include "nav/navigator.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>

#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/esc_catalog.hpp"

namespace concert::nav {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kDbDir = fs::path(CONCERT_SOURCE_DIR) / "data" / "module_db";

std::shared_ptr<const model::RobotModel> demo_model(std::uint64_t version) {
  static const module_db::ModuleDatabase db = module_db::load_module_database(kDbDir);
  static const topology::EscCatalog catalog = topology::EscCatalog::load(kDbDir);
  const auto assembly =
      simbus::load_assembly(fs::path(CONCERT_SOURCE_DIR) / "deploy" / "demo" / "drill_robot.yaml");
  model_generation::GeneratedModel m =
      model_generation::ModelGenerator(db).generate(simbus::tree_from_assembly(assembly, catalog));
  m.version = version;
  return model::RobotModel::build(m.description());
}

// Two 7 m x 5 m rooms side by side (x in [0, 7] and [7.2, 14.2]), a 0.2 m wall between them with
// a 2 m door at y in [1.5, 3.5]; 5 cm cells.
bim::OccupancyGrid two_rooms() {
  auto g = bim::OccupancyGrid::filled(300, 120, 0.05, {-0.5, -0.5});
  auto wall = [&](double x0, double y0, double x1, double y1) {
    for (int r = 0; r < g.height; ++r) {
      for (int c = 0; c < g.width; ++c) {
        const Eigen::Vector2d p = g.center_of(c, r);
        if (p.x() >= x0 && p.x() <= x1 && p.y() >= y0 && p.y() <= y1)
          g.at(c, r) = bim::OccupancyGrid::kOccupied;
      }
    }
  };
  wall(-0.2, -0.2, 14.4, 0.0);  // south
  wall(-0.2, 5.0, 14.4, 5.2);   // north
  wall(-0.2, -0.2, 0.0, 5.2);   // west
  wall(14.2, -0.2, 14.4, 5.2);  // east
  wall(7.0, -0.2, 7.2, 1.5);    // the middle wall, below the door
  wall(7.0, 3.5, 7.2, 5.2);     // ... and above it
  return g;
}

// A planar scan of the demo robot's derived scan: 720 beams, 0.1..30 m, in the true map.
PlanarScan scan_at(const bim::OccupancyGrid& truth, const Eigen::Vector3d& pose,
                   std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 0.01);
  PlanarScan s;
  s.range_min = 0.1;
  s.range_max = 30.0;
  for (int i = 0; i < 720; ++i) {
    const double a = -M_PI + i * (2.0 * M_PI / 720.0);
    const double r = cast_ray(truth, pose.head<2>(), pose.z() + a, s.range_max);
    s.angles.push_back(a);
    s.ranges.push_back(r >= s.range_max ? std::numeric_limits<double>::infinity() : r + noise(rng));
  }
  return s;
}

struct Drive {
  Eigen::Vector3d truth;          // map frame
};

// Runs the navigator closed-loop for up to `seconds` of simulated time at 100 Hz odometry, 10 Hz
// scans and the control rate; the base follows the command with a first-order lag and its wheels
// slip 2 % in speed. Returns the final status.
// `on_command` sees every command with its stamp.
GoalStatus run(Navigator& nav, Drive& d, const bim::OccupancyGrid& truth, double seconds,
               std::mt19937& rng,
               const std::function<void(double, const BaseTwist&)>& on_command = {}) {
  const double dt = 0.01;
  BaseTwist cmd;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int k = 0; k < static_cast<int>(seconds / dt); ++k) {
    const double t = 10.0 + k * dt;
    // The base: a lag of 0.1 s to the command, exact integration in the true map.
    v += (Eigen::Vector3d(cmd.vx, cmd.vy, cmd.wz) - v) * (dt / 0.1);
    d.truth = integrate_twist(d.truth, {v.x(), v.y(), v.z()}, dt);
    const Eigen::Vector3d measured = v.cwiseProduct(Eigen::Vector3d(1.02, 1.02, 0.98));  // slip
    nav.on_wheel_odometry(t, measured);
    nav.on_gyro(t, v.z() + 0.002);  // a small gyro bias
    if (k % 10 == 0) nav.on_scan(t, scan_at(truth, d.truth, rng));
    if (k % 5 == 0) {
      const StepOutput out = nav.step(t);
      cmd = out.drive ? out.command : BaseTwist{};
      if (on_command) on_command(t, cmd);
      const auto s = nav.status().state;
      if (s == GoalState::kReached || s == GoalState::kFailed || s == GoalState::kCancelled) break;
    }
  }
  return nav.status();
}

class NavigatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = demo_model(3);
    nav_.set_model(*model_);
    nav_.set_map(map_, "two rooms");
  }
  // Odometry and a first scan at the start, then the user's initial pose (off by 10 cm, 3 deg).
  void start(const Eigen::Vector3d& truth) { start(nav_, truth); }
  void start(Navigator& nav, const Eigen::Vector3d& truth) {
    drive_.truth = truth;
    nav.on_wheel_odometry(9.99, Eigen::Vector3d::Zero());
    nav.set_initial_pose({truth.x() + 0.1, truth.y() - 0.05, truth.z() + 0.05}, 0.0, 0.0);
    for (int i = 0; i < 5; ++i) {
      nav.on_scan(9.99, scan_at(map_, truth, rng_));
      nav.step(9.99);
    }
  }
  GoalRequest goal(double x, double y, double yaw, std::uint32_t id = 7) {
    GoalRequest g;
    g.id = id;
    g.model_version = 3;
    g.pose = {x, y, yaw};
    return g;
  }
  std::mt19937 rng_{42};
  bim::OccupancyGrid map_ = two_rooms();
  std::shared_ptr<const model::RobotModel> model_;
  Navigator nav_{NavParams{}, 5};
  Drive drive_;
};

TEST_F(NavigatorTest, DrivesThroughTheDoorAndStopsWithinTolerance) {
  start({2.0, 2.5, 0.0});
  const GoalStatus accepted = nav_.submit(goal(11.5, 3.0, M_PI / 2));
  ASSERT_EQ(accepted.state, GoalState::kPlanning) << accepted.reason;
  const GoalStatus s = run(nav_, drive_, map_, 120.0, rng_);
  ASSERT_EQ(s.state, GoalState::kReached) << s.reason;
  // Against the truth, not the navigator's own estimate.
  EXPECT_LT(std::hypot(drive_.truth.x() - 11.5, drive_.truth.y() - 3.0), 0.05)
      << "true final pose " << drive_.truth.transpose();
  EXPECT_LT(std::abs(std::remainder(drive_.truth.z() - M_PI / 2, 2 * M_PI)),
            2.0 * M_PI / 180.0 + 0.01);
  // The path went through the door.
  bool through_door = false;
  for (const auto& p : nav_.path())
    through_door |= p.x() > 6.9 && p.x() < 7.3 && p.y() > 1.5 && p.y() < 3.5;
  EXPECT_TRUE(through_door);
}

// The demo arm riding on the base, stretched out, cannot hold the platform's 1 rad/s^2 turn within
// its continuous torques (a safety stop, measured before the drive budget existed): the navigator
// turns no faster than the budget at the posture it is sent, says which joint sets it, and still
// arrives.
TEST_F(NavigatorTest, TurnsTheBaseNoFasterThanTheArmItCarriesCanHold) {
  const model::DriveBudget drives(*model_);
  const std::vector<std::string>& names = drives.joint_names();
  const model::ChainInfo& arm = model_->arm();
  // The shoulder (the arm's second joint) swept from upright to either side, the other joints
  // at 0: the posture whose budget is nearest half the platform's accelerations. The arm then
  // holds most of its continuous torque against gravity, and a brake or a turn adds the rest.
  const NavParams params;
  const model::BaseMotion asked{params.max_acceleration, params.max_acceleration,
                                params.max_angular_acceleration, nav_.vehicle()->limits.angular};
  const auto shoulder = std::find(names.begin(), names.end(), arm.joints.at(1)) - names.begin();
  const model::JointLimits& limits = model_->limits().at(arm.joints.at(1));
  Eigen::VectorXd worst = drives.neutral_posture();
  double worst_scale = 1.0;
  for (int k = -300; k <= 300; ++k) {
    Eigen::VectorXd q = drives.neutral_posture();
    q(shoulder) = std::clamp(0.01 * k, limits.lower, limits.upper);
    const model::BaseBudget b = drives.base_motion(q, asked, 1.0);
    if (b.holds_static && std::abs(b.scale - 0.5) < std::abs(worst_scale - 0.5)) {
      worst_scale = b.scale;
      worst = q;
    }
  }
  const model::BaseBudget budget = drives.base_motion(worst, asked, 1.0);
  ASSERT_LT(budget.scale, 0.9) << "no posture of the demo arm's shoulder limits the base";
  ASSERT_GT(budget.scale, 0.01) << budget.joint << " is overloaded standing still";
  std::cout << "demo arm leaning: " << 100.0 * budget.scale << " % of the base's accelerations, set by "
            << budget.joint << " (" << 100.0 * budget.static_load << " % still, " << 100.0 * budget.dynamic_load
            << " % more at full)\n";

  // Away from its transport posture, the arm is not driven at all: the goal is refused naming
  // the joint and the way home.
  start({2.0, 2.5, 0.0});
  nav_.on_joint_positions(names, std::vector<double>(worst.data(), worst.data() + worst.size()));
  const GoalStatus refused = nav_.submit(goal(2.0, 2.5, M_PI));
  EXPECT_EQ(refused.state, GoalState::kRefused);
  EXPECT_THAT(refused.reason, HasSubstr("not in its transport posture"));
  EXPECT_THAT(refused.reason, HasSubstr(arm.joints.at(1) + " at "));
  EXPECT_THAT(refused.reason, HasSubstr("concert plan home"));

  // A robot whose transport posture leans so (the check off): the budget rules the turn.
  NavParams carried_params;
  carried_params.arm_home_tolerance = 0.0;
  Navigator carried(carried_params, 5);
  carried.set_model(*model_);
  carried.set_map(map_, "two rooms");
  start(carried, {2.0, 2.5, 0.0});
  carried.on_joint_positions(names, std::vector<double>(worst.data(), worst.data() + worst.size()));
  ASSERT_EQ(carried.submit(goal(2.0, 2.5, M_PI)).state, GoalState::kPlanning);
  std::vector<std::pair<double, double>> yaw_rates;  // (stamp, commanded wz)
  const GoalStatus s = run(carried, drive_, map_, 60.0, rng_,
                           [&](double t, const BaseTwist& c) { yaw_rates.emplace_back(t, c.wz); });
  ASSERT_EQ(s.state, GoalState::kReached) << s.reason;
  EXPECT_NEAR(carried.drive_budget().scale, budget.scale, 1e-9);
  EXPECT_EQ(carried.drive_budget().joint, budget.joint);
  // The commands' yaw acceleration stays within the budget. The last command, the stop at the
  // goal, is a step to zero (within the heading tolerance; the wheels' drives take it).
  ASSERT_GE(yaw_rates.size(), 3u);
  double steepest = 0.0;
  for (std::size_t i = 1; i + 1 < yaw_rates.size(); ++i) {
    const double dt = yaw_rates[i].first - yaw_rates[i - 1].first;
    steepest = std::max(steepest, std::abs(yaw_rates[i].second - yaw_rates[i - 1].second) / dt);
  }
  EXPECT_EQ(yaw_rates.back().second, 0.0);
  EXPECT_LE(steepest, params.max_angular_acceleration * budget.scale + 1e-6);
  EXPECT_GT(steepest, 0.5 * params.max_angular_acceleration * budget.scale) << "it hardly turned";
  const std::string note = carried.take_budget_note();
  EXPECT_THAT(note, HasSubstr(budget.joint));
  EXPECT_THAT(note, HasSubstr("% of the configured"));

  // A posture no drive can hold still leaves no acceleration: the goal fails naming the joint.
  Eigen::VectorXd overload = worst;
  NavParams strict;
  strict.drive_torque_fraction = 1e-3;
  strict.arm_home_tolerance = 0.0;
  Navigator weak(strict, 5);
  weak.set_model(*model_);
  weak.set_map(map_, "two rooms");
  weak.on_joint_positions(names, std::vector<double>(overload.data(), overload.data() + overload.size()));
  weak.on_wheel_odometry(9.99, Eigen::Vector3d::Zero());
  weak.set_initial_pose({2.0, 2.5, 0.0}, 0.0, 0.0);
  for (int i = 0; i < 5; ++i) {
    weak.on_scan(9.99, scan_at(map_, {2.0, 2.5, 0.0}, rng_));
    weak.step(9.99);
  }
  ASSERT_EQ(weak.submit(goal(2.0, 2.5, M_PI)).state, GoalState::kPlanning);
  weak.step(10.0);
  weak.step(10.05);
  EXPECT_EQ(weak.status().state, GoalState::kFailed);
  EXPECT_THAT(weak.status().reason, HasSubstr("leaves the base no acceleration"));
}

TEST_F(NavigatorTest, RefusesWhatItCannotDoWithAReason) {
  // Not localised yet.
  nav_.on_wheel_odometry(1.0, Eigen::Vector3d::Zero());
  EXPECT_THAT(nav_.submit(goal(3, 3, 0)).reason, HasSubstr("not localised"));
  start({2.0, 2.5, 0.0});
  // A goal for another model version.
  GoalRequest stale = goal(3, 3, 0);
  stale.model_version = 2;
  EXPECT_THAT(nav_.submit(stale).reason, HasSubstr("stale goal: made for model version 2"));
  // Inside the middle wall; outside the map.
  const GoalStatus in_wall = nav_.submit(goal(7.1, 0.8, 0));
  EXPECT_EQ(in_wall.state, GoalState::kRefused);
  EXPECT_THAT(in_wall.reason, HasSubstr("in collision"));
  EXPECT_THAT(nav_.submit(goal(40, 3, 0)).reason, HasSubstr("outside the map"));
  // Wall goals need the BIM model.
  GoalRequest wall = goal(3, 3, 0);
  wall.kind = GoalRequest::Kind::kWall;
  wall.wall = "2O2Fr$t4X7Zf8NOew3FLOH";
  EXPECT_THAT(nav_.submit(wall).reason, HasSubstr("IFC model"));
  // Each refusal was reported.
  int refused = 0;
  for (const auto& u : nav_.take_updates()) refused += u.state == GoalState::kRefused;
  EXPECT_EQ(refused, 5);
}

TEST_F(NavigatorTest, SafetyStopCancelsAndGoalsWaitForTheReset) {
  start({2.0, 2.5, 0.0});
  ASSERT_EQ(nav_.submit(goal(5.0, 2.5, 0)).state, GoalState::kPlanning);
  run(nav_, drive_, map_, 1.0, rng_);
  EXPECT_EQ(nav_.status().state, GoalState::kFollowing);
  nav_.set_safety_stop(true, "safety stop: estop: wireless");
  EXPECT_EQ(nav_.status().state, GoalState::kCancelled);
  EXPECT_THAT(nav_.status().reason, HasSubstr("estop"));
  // One zero command after the goal ended, then nothing.
  const StepOutput after = nav_.step(20.0);
  EXPECT_TRUE(after.drive);
  EXPECT_EQ(after.command.vx, 0.0);
  EXPECT_FALSE(nav_.step(20.05).drive);
  EXPECT_THAT(nav_.submit(goal(5.0, 2.5, 0, 8)).reason, HasSubstr("safety stop"));
  nav_.set_safety_stop(false, "");
  EXPECT_EQ(nav_.submit(goal(5.0, 2.5, 0, 9)).state, GoalState::kPlanning);
}

TEST_F(NavigatorTest, ANewModelCancelsTheGoalAndStaleGoalsAreRefused) {
  start({2.0, 2.5, 0.0});
  ASSERT_EQ(nav_.submit(goal(5.0, 2.5, 0)).state, GoalState::kPlanning);
  nav_.set_model(*demo_model(4));
  EXPECT_EQ(nav_.status().state, GoalState::kCancelled);
  EXPECT_THAT(nav_.status().reason, HasSubstr("model changed to version 4"));
  EXPECT_THAT(nav_.submit(goal(5.0, 2.5, 0, 8)).reason, HasSubstr("stale goal"));
  GoalRequest fresh = goal(5.0, 2.5, 0, 9);
  fresh.model_version = 4;
  EXPECT_EQ(nav_.submit(fresh).state, GoalState::kPlanning);
}

// An IMU sample in the IMU's own frame counts as the gyro rate about the base's z once turned by
// the IMU's mounting; an IMU the vehicle does not know is taken as aligned with the base.
TEST_F(NavigatorTest, AnImuSampleIsTurnedIntoTheBaseFrameByItsMounting) {
  ASSERT_NE(nav_.vehicle(), nullptr);
  ASSERT_FALSE(nav_.vehicle()->perception.imus.empty());
  const SensorPose imu = nav_.vehicle()->perception.imus.front();
  // The base's yaw rate as the vehicle's IMU, as mounted, measures it.
  Navigator mounted{NavParams{}, 5}, unknown{NavParams{}, 5}, gyro{NavParams{}, 5};
  for (Navigator* n : {&mounted, &unknown, &gyro}) n->set_model(*model_);
  const Eigen::Matrix3d base_R_imu = imu.base_T_sensor.linear();
  const double wz = 0.3;
  for (int k = 0; k <= 100; ++k) {
    const double t = 1.0 + 0.01 * k;
    for (Navigator* n : {&mounted, &unknown, &gyro}) n->on_wheel_odometry(t, Eigen::Vector3d(0.0, 0.0, 0.25));
    gyro.on_gyro(t, wz);
    mounted.on_imu(t, imu.name, "", base_R_imu.transpose() * Eigen::Vector3d(0.0, 0.0, wz));
    unknown.on_imu(t, "no_such_imu", "no_such_frame", Eigen::Vector3d(0.0, 0.0, wz));
  }
  EXPECT_NEAR(mounted.odometry().pose.z(), gyro.odometry().pose.z(), 1e-9);
  EXPECT_NEAR(unknown.odometry().pose.z(), gyro.odometry().pose.z(), 1e-9);
  // A rate about the IMU's other axes adds nothing when the IMU is aligned with the base.
  Navigator sideways{NavParams{}, 5};
  sideways.set_model(*model_);
  for (int k = 0; k <= 100; ++k) {
    const double t = 1.0 + 0.01 * k;
    sideways.on_wheel_odometry(t, Eigen::Vector3d(0.0, 0.0, 0.25));
    sideways.on_imu(t, "no_such_imu", "", Eigen::Vector3d(0.5, -0.5, wz));
  }
  EXPECT_NEAR(sideways.odometry().pose.z(), gyro.odometry().pose.z(), 1e-9);
}

TEST(NavParams, TheShippedFileHoldsEveryDefault) {
  const NavParams p = load_params(NAV_CONFIG);
  const NavParams d;
  EXPECT_EQ(p.control_rate, d.control_rate);
  EXPECT_EQ(p.localiser.particles, d.localiser.particles);
  EXPECT_NEAR(p.controller.yaw_goal_tolerance, d.controller.yaw_goal_tolerance, 1e-4);
  EXPECT_EQ(p.costmap.inflation_radius, d.costmap.inflation_radius);
}

TEST(NavParams, ABadKeyIsNamed) {
  const fs::path file = fs::temp_directory_path() / "nav_bad_params.yaml";
  {
    std::ofstream out(file);
    out << "controller:\n  lookahed_time: 1.0\n";
  }
  try {
    load_params(file.string());
    FAIL() << "accepted an unknown key";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("lookahed_time"));
  }
}

}  // namespace
}  // namespace concert::nav
