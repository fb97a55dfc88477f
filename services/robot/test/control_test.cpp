// The "done when" scenarios, in simulated time (faster than real time).
#include <gtest/gtest.h>

#include <cmath>

#include "robot/robot_core.hpp"
#include "test_helpers.hpp"

namespace concert::robot {
namespace {

using test::hw_index;
using test::read_fixture;
using test::run_cycles;

// Documented bound (README): a joint impedance step designed for damping ratio 0.8 on the
// model's inertia (+ drive armature) overshoots by less than 10 % of the step and settles
// within 2 % of the step in under 1.5 s.
constexpr double kMaxOvershoot = 0.10;

TEST(JointImpedance, StepResponseSettlesWithBoundedOvershoot) {
  test::SimulatedArm arm({{"J2_A", 0.3}, {"J3_A", 0.5}}, 300);
  RobotCore& core = arm.core;
  const auto model = core.model();
  auto data = model->make_data();
  RobotState s = core.state();
  Eigen::VectorXd q(model->dof());
  for (int i = 0; i < model->dof(); ++i) {
    q(i) = s.position[hw_index(s, model->joint_names()[static_cast<std::size_t>(i)])];
  }
  const int j2 = model->joint_index_or_throw("J2_A");
  const double start = q(j2);
  const double step = 0.3;
  Eigen::VectorXd q_target = q;
  q_target(j2) += step;
  const double stiffness = 400.0;
  const double inertia = model->mass_matrix(data, q_target)(j2, j2) + SimParams{}.armature;
  const double damping = 2.0 * 0.8 * std::sqrt(stiffness * inertia);
  const double gravity_ff = model->gravity_torques(data, q_target)(j2);
  core.command_joints({1, {{"J2_A", DriveMode::kImpedance, start + step, 0.0, gravity_ff, stiffness, damping}}});
  double peak = start;
  double settle_time = -1.0;
  for (int k = 0; k < 3000; ++k) {
    core.cycle();
    s = core.state();
    const double pos = s.position[hw_index(s, "J2_A")];
    peak = std::max(peak, pos);
    const bool inside = std::abs(pos - (start + step)) < 0.02 * step;
    if (inside && settle_time < 0.0) {
      settle_time = k * 0.001;
    } else if (!inside) {
      settle_time = -1.0;
    }
  }
  const double overshoot = (peak - (start + step)) / step;
  EXPECT_LT(overshoot, kMaxOvershoot) << "peak " << peak;
  EXPECT_GT(peak, start + 0.9 * step);  // it did move
  EXPECT_GE(settle_time, 0.0);
  EXPECT_LT(settle_time, 1.5);
}

// An arm pressing its drill tip on a wall: Cartesian impedance holds the pose and the
// wrench estimated from joint torques matches the contact force MuJoCo computes.
class WallContact : public ::testing::Test {
 protected:
  void SetUp() override {
    // Drill pointing horizontally along +x (pitches sum to 90 degrees).
    params_.initial_positions = {{"J2_A", 0.3}, {"J3_A", 1.0}, {"J5_B", M_PI / 2 - 1.3}};
    const auto model = kinematics::Model::from_urdf_string(read_fixture("arm_drill.urdf"));
    auto data = model.make_data();
    Eigen::VectorXd q = Eigen::VectorXd::Zero(model.dof());
    for (const auto& [name, value] : params_.initial_positions) {
      q(model.joint_index_or_throw(name)) = value;
    }
    tcp0_ = model.frame_pose(data, q, "tcp");
    // Wall face 1 cm beyond the tip sphere (radius 2 cm around the tcp).
    WorldShape wall;
    wall.name = "wall";
    wall.size = {0.2, 2.0, 2.0};
    wall.position = {tcp0_.translation().x() + 0.03 + 0.1, 0.0, 1.0};
    world_.walls.push_back(wall);
    sim_ = std::make_unique<SimHardware>(read_fixture("arm_drill.urdf"), world_, params_);
    core_ = std::make_unique<RobotCore>(*sim_);
    core_->set_model(read_fixture("arm_drill.urdf"), 1);
    run_cycles(*core_, 200);
  }

  CartesianCommand press(double depth) const {
    CartesianCommand c;
    c.model_version = 1;
    c.target_pose = tcp0_;
    c.target_pose.translation().x() += depth;
    c.stiffness << 1000, 1000, 1000, 100, 100, 100;
    c.damping << 100, 100, 100, 10, 10, 10;
    return c;
  }

  Eigen::Vector3d contact_force() const { return sim_->contact_force_on({"drill", "tcp"}); }

  SimParams params_;
  World world_;
  Eigen::Isometry3d tcp0_;
  std::unique_ptr<SimHardware> sim_;
  std::unique_ptr<RobotCore> core_;
};

TEST_F(WallContact, CartesianImpedanceHoldsThePoseAndEstimatesTheContactForce) {
  core_->command_cartesian(press(0.0));
  run_cycles(*core_, 500);
  RobotState s = core_->state();
  EXPECT_LT((s.end_effector_pose.translation() - tcp0_.translation()).norm(), 0.005);
  EXPECT_LT(contact_force().norm(), 1e-6);  // not touching yet
  // Push 5 cm into the wall: ~1000 N/m * 4 cm = 40 N.
  core_->command_cartesian(press(0.05));
  run_cycles(*core_, 2000);
  s = core_->state();
  const Eigen::Vector3d truth = contact_force();
  const Eigen::Vector3d estimate = s.end_effector_wrench.head<3>();
  EXPECT_GT(-truth.x(), 25.0) << truth.transpose();  // the wall pushes back along -x
  EXPECT_LT((estimate - truth).norm(), 0.10 * truth.norm())
      << "estimate " << estimate.transpose() << " truth " << truth.transpose();
  // The pose is held at the wall: tip touching, orientation and lateral position kept.
  EXPECT_NEAR(s.end_effector_pose.translation().x(), tcp0_.translation().x() + 0.01, 0.005);
  EXPECT_NEAR(s.end_effector_pose.translation().y(), tcp0_.translation().y(), 0.005);
  EXPECT_NEAR(s.end_effector_pose.translation().z(), tcp0_.translation().z(), 0.005);
  EXPECT_LT(Eigen::AngleAxisd(s.end_effector_pose.linear() * tcp0_.linear().transpose()).angle(), 0.02);
}

TEST_F(WallContact, AdmittanceAlongOneAxisRegulatesTheContactForce) {
  CartesianCommand c = press(0.0);
  c.admittance.enabled = true;
  c.admittance.axis = Eigen::Vector3d::UnitX();
  c.admittance.force_setpoint = 30.0;
  core_->command_cartesian(c);
  run_cycles(*core_, 4000);
  const Eigen::Vector3d truth = contact_force();
  EXPECT_NEAR(-truth.x(), 30.0, 3.0) << truth.transpose();
}

TEST_F(WallContact, WrenchEstimateWithinTenPercentWithSensorNoise) {
  // Same press, with encoder (1e-5 rad) and torque-sensor (0.1 N m) noise.
  params_.position_noise = 1e-5;
  params_.effort_noise = 0.1;
  params_.seed = 7;
  sim_ = std::make_unique<SimHardware>(read_fixture("arm_drill.urdf"), world_, params_);
  core_ = std::make_unique<RobotCore>(*sim_);
  core_->set_model(read_fixture("arm_drill.urdf"), 1);
  run_cycles(*core_, 200);
  core_->command_cartesian(press(0.05));
  run_cycles(*core_, 2000);
  const Eigen::Vector3d truth = contact_force();
  const Eigen::Vector3d estimate = core_->state().end_effector_wrench.head<3>();
  EXPECT_GT(-truth.x(), 25.0);
  EXPECT_LT((estimate - truth).norm(), 0.10 * truth.norm())
      << "estimate " << estimate.transpose() << " truth " << truth.transpose();
}

class MobileBase : public ::testing::Test {
 protected:
  explicit MobileBase(World world = {}, SimParams params = {})
      : sim_(read_fixture("mobile_drill.urdf"), std::move(world), std::move(params)), core_(sim_) {
    core_.set_model(read_fixture("mobile_drill.urdf"), 1);
    run_cycles(core_, 200);
  }
  // Drives the base at (vx, vy, wz) for `seconds` of simulated time.
  void drive(double vx, double vy, double wz, double seconds) {
    test::drive_base(core_, {1, vx, vy, wz}, static_cast<int>(seconds * 1000));
  }
  SimHardware sim_;
  RobotCore core_;
};

TEST_F(MobileBase, ForwardCommandGivesForwardMotionInOdometry) {
  drive(0.3, 0.0, 0.0, 4.0);
  const RobotState s = core_.state();
  EXPECT_NEAR(s.odometry.vx, 0.3, 0.015);
  EXPECT_NEAR(s.odometry.vy, 0.0, 0.015);
  EXPECT_NEAR(s.odometry.wz, 0.0, 0.02);
  // ~0.3 m/s for 4 s minus the start-up; odometry agrees with the simulated base pose.
  EXPECT_GT(s.odometry.x, 1.0);
  const Eigen::Vector3d truth = sim_.base_pose().translation();
  EXPECT_NEAR(s.odometry.x, truth.x(), 0.05 * truth.x());
  EXPECT_NEAR(s.odometry.y, truth.y(), 0.03);
}

TEST_F(MobileBase, SidewaysAndTurningCommands) {
  drive(0.0, 0.25, 0.0, 3.0);
  RobotState s = core_.state();
  EXPECT_NEAR(s.odometry.vy, 0.25, 0.015);
  EXPECT_NEAR(s.odometry.vx, 0.0, 0.015);
  EXPECT_NEAR(s.odometry.y, sim_.base_pose().translation().y(), 0.05);
  const double yaw0 = s.odometry.yaw;
  drive(0.0, 0.0, 0.4, 3.0);
  s = core_.state();
  EXPECT_NEAR(s.odometry.wz, 0.4, 0.03);
  const Eigen::Matrix3d r = sim_.base_pose().linear();
  const double true_yaw = std::atan2(r(1, 0), r(0, 0));
  EXPECT_GT(s.odometry.yaw - yaw0, 0.8);
  EXPECT_NEAR(s.odometry.yaw, true_yaw, 0.1);
  // The base stops when commands stop.
  run_cycles(core_, 1500);
  s = core_.state();
  EXPECT_NEAR(s.odometry.wz, 0.0, 0.01);
}

class SlipperyFloor : public MobileBase {
 protected:
  static World ice() {
    World w;
    w.floor_friction = 0.02;
    return w;
  }
  static SimParams worn_tyres() {
    SimParams p;
    p.wheel_friction = 0.02;  // MuJoCo uses the larger friction of the two geoms in contact
    return p;
  }
  SlipperyFloor() : MobileBase(ice(), worn_tyres()) {}
};

TEST_F(SlipperyFloor, WheelsSlipAndOdometryOverestimates) {
  // Wheel-floor contact is simulated, not scripted: on ice the wheels spin faster than the
  // base moves, and wheel odometry (rolling without slip) runs ahead of the true motion.
  drive(0.5, 0.0, 0.0, 2.0);
  const RobotState s = core_.state();
  const double truth = sim_.base_pose().translation().x();
  EXPECT_GT(s.odometry.x, 0.5);
  EXPECT_LT(truth, 0.8 * s.odometry.x) << "odometry " << s.odometry.x << " truth " << truth;
}

}  // namespace
}  // namespace concert::robot
