// The impedance law and the wrench estimate (impedance.hpp) against what they must give by
// construction: a pure stiffness pulls along the error, a wrench comes back from the torques it
// makes, and the filter's step.
#include "concert/kinematics/impedance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace concert::kinematics {
namespace {

TEST(Impedance, RotationErrorIsTheRotationVectorToTheTarget) {
  const Eigen::Matrix3d current = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d target =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix() * current;
  EXPECT_TRUE(rotation_error(target, current).isApprox(Eigen::Vector3d(0.0, 0.0, 0.5), 1e-12));
  EXPECT_TRUE(rotation_error(current, current).isZero(1e-12));
}

TEST(Impedance, TheWrenchIsStiffnessTimesTheErrorPlusDampingTimesTheTwistError) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.5, 0.1, 1.0);
  Eigen::Isometry3d target = pose;
  target.translation() += Eigen::Vector3d(0.01, -0.02, 0.0);
  target.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
  Vector6d k, d, twist, target_twist;
  k << 1000, 2000, 3000, 50, 60, 70;
  d << 10, 20, 30, 1, 2, 3;
  twist << 0.1, 0, 0, 0, 0, 0.2;
  target_twist << 0, 0.05, 0, 0, 0, 0;
  Vector6d expected;
  expected << 1000 * 0.01 + 10 * -0.1, 2000 * -0.02 + 20 * 0.05, 0, 0, 60 * 0.1, 3 * -0.2;
  EXPECT_TRUE(impedance_wrench(pose, target, twist, target_twist, k, d).isApprox(expected, 1e-12));
}

TEST(Impedance, AWrenchComesBackFromTheTorquesItMakes) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd jac(6, 7);
  for (Eigen::Index i = 0; i < jac.size(); ++i) jac.data()[i] = u(rng);
  Vector6d wrench;
  wrench << 12.0, -3.0, 40.0, 1.5, -0.5, 0.2;
  Eigen::VectorXd tau(7);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(7);
  wrench_torques(jac, wrench, still, 2.0, tau);
  EXPECT_TRUE(tau.isApprox(jac.transpose() * wrench, 1e-12));
  // Full-rank J: the damped least squares gives the wrench back to within its damping.
  EXPECT_TRUE(wrench_from_residual(jac, tau).isApprox(wrench, 1e-5));
  // The joints' own motion is damped.
  const Eigen::VectorXd qd = Eigen::VectorXd::Constant(7, 0.5);
  wrench_torques(jac, Vector6d::Zero(), qd, 2.0, tau);
  EXPECT_TRUE(tau.isApprox(Eigen::VectorXd::Constant(7, -1.0), 1e-12));
}

TEST(Impedance, TheLowPassMovesByDtOverTauPlusDt) {
  const Vector6d raw = Vector6d::Constant(1.0);
  EXPECT_TRUE(low_pass(Vector6d::Zero(), raw, 0.001, 0.02).isApprox(Vector6d::Constant(0.001 / 0.021), 1e-12));
  EXPECT_TRUE(low_pass(Vector6d::Zero(), raw, 0.001, 0.0).isApprox(raw));
}

}  // namespace
}  // namespace concert::kinematics
