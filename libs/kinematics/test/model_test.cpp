#include "concert/kinematics/model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>
#include <thread>

namespace concert::kinematics {
namespace {

const std::string kFixtures = KINEMATICS_FIXTURES;
constexpr double kG = 9.81;
constexpr double kL1 = 0.5, kL2 = 0.4, kM1 = 2.0, kM2 = 1.5;

Model two_link() { return Model::from_urdf_file(kFixtures + "/two_link.urdf"); }
Model mobile_drill(bool planar) {
  ModelOptions options;
  options.planar_base = planar;
  return Model::from_urdf_file(kFixtures + "/mobile_drill.urdf", options);
}

Eigen::VectorXd random_q(const Model& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  Eigen::VectorXd q(model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    q(i) = u(rng);
  }
  return q;
}

// Orientation error as a rotation vector (small angles).
Eigen::Vector3d rotation_difference(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::AngleAxisd aa(a * b.transpose());
  return aa.angle() * aa.axis();
}

TEST(KinematicsModel, JointOrderLimitsAndMass) {
  const Model m = two_link();
  EXPECT_EQ(m.name(), "two_link");
  ASSERT_EQ(m.dof(), 2);
  EXPECT_EQ(m.joint_names(), (std::vector<std::string>{"j1", "j2"}));
  EXPECT_EQ(m.joint_types()[0], JointType::kRevolute);
  EXPECT_EQ(m.joint_types()[1], JointType::kContinuous);
  EXPECT_TRUE(m.joint_limits()[0].has_position_limits);
  EXPECT_DOUBLE_EQ(m.joint_limits()[0].lower, -3.0);
  EXPECT_DOUBLE_EQ(m.joint_limits()[0].upper, 3.0);
  EXPECT_DOUBLE_EQ(m.joint_limits()[0].effort, 50.0);
  EXPECT_DOUBLE_EQ(m.joint_limits()[0].velocity, 2.0);
  EXPECT_FALSE(m.joint_limits()[1].has_position_limits);
  EXPECT_DOUBLE_EQ(m.joint_limits()[1].effort, 30.0);
  EXPECT_NEAR(m.total_mass(), 1.0 + kM1 + kM2, 1e-12);
  EXPECT_TRUE(m.has_frame("tip"));
  EXPECT_TRUE(m.has_frame("world"));
  EXPECT_FALSE(m.has_frame("nope"));
  EXPECT_EQ(m.root_link(), "base");
  EXPECT_EQ(*m.joint_index("j2"), 1);
  EXPECT_FALSE(m.joint_index("j3").has_value());
}

TEST(KinematicsModel, DepthFirstJointOrderOnTree) {
  const Model m = mobile_drill(false);
  ASSERT_EQ(m.dof(), 4 * 2 + 6);
  // Depth-first: every steering joint is directly followed by its wheel joint.
  for (const std::string leg : {"fl", "fr", "rl", "rr"}) {
    const int s = m.joint_index_or_throw("J_steer_" + leg);
    EXPECT_EQ(m.joint_names()[s + 1], "J_wheel_" + leg);
    EXPECT_EQ(m.descendant_joints(s), std::vector<int>{s + 1});
  }
  EXPECT_EQ(m.joint_child_link(m.joint_index_or_throw("J6_B")), "arm_link_6");
  EXPECT_EQ(m.joint_parent_link(m.joint_index_or_throw("J1_A")), "arm_base");
  EXPECT_TRUE(m.joint_axis(m.joint_index_or_throw("J_wheel_fl")).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(m.total_mass(), 80.0 + 4 * 7.0 + 2.0 + 3.6 + 3.0 + 2.5 + 1.5 + 1.2 + 0.8 + 2.0, 1e-9);
}

/// The two-link arm whose kinematics and dynamics are computed by hand below.
class TwoLinkArm : public ::testing::Test {
 protected:
  const Model model_ = two_link();
  Data data_ = model_.make_data();
};

TEST_F(TwoLinkArm, ForwardKinematicsMatchesHandComputation) {
  std::mt19937 rng(7);
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd q = random_q(model_, rng);
    const Eigen::Isometry3d tip = model_.frame_pose(data_, q, "tip");
    // Rotation about +y turns +x towards -z.
    const double x = kL1 * std::cos(q(0)) + kL2 * std::cos(q(0) + q(1));
    const double z = -(kL1 * std::sin(q(0)) + kL2 * std::sin(q(0) + q(1)));
    EXPECT_NEAR(tip.translation().x(), x, 1e-12);
    EXPECT_NEAR(tip.translation().y(), 0.0, 1e-12);
    EXPECT_NEAR(tip.translation().z(), z, 1e-12);
    const Eigen::Matrix3d expected = Eigen::AngleAxisd(q(0) + q(1), Eigen::Vector3d::UnitY()).toRotationMatrix();
    EXPECT_TRUE(tip.linear().isApprox(expected, 1e-12));
    const Eigen::Isometry3d rel = model_.relative_pose(data_, q, "link2", "tip");
    EXPECT_TRUE(rel.translation().isApprox(Eigen::Vector3d(kL2, 0, 0), 1e-12));
  }
}

TEST_F(TwoLinkArm, GravityAndDynamicsMatchHandComputation) {
  std::mt19937 rng(11);
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd q = random_q(model_, rng);
    const Eigen::VectorXd qd = random_q(model_, rng);
    const Eigen::VectorXd qdd = random_q(model_, rng);
    const double c1 = std::cos(q(0)), c12 = std::cos(q(0) + q(1)), c2 = std::cos(q(1)), s2 = std::sin(q(1));
    Eigen::Vector2d g;
    g << -kG * (kM1 * kL1 * c1 + kM2 * (kL1 * c1 + kL2 * c12)), -kG * kM2 * kL2 * c12;
    EXPECT_TRUE(model_.gravity_torques(data_, q).isApprox(g, 1e-6))
        << model_.gravity_torques(data_, q).transpose() << " vs " << g.transpose();
    Eigen::Matrix2d mm;
    mm(0, 0) = kM1 * kL1 * kL1 + kM2 * (kL1 * kL1 + kL2 * kL2 + 2 * kL1 * kL2 * c2);
    mm(0, 1) = mm(1, 0) = kM2 * (kL2 * kL2 + kL1 * kL2 * c2);
    mm(1, 1) = kM2 * kL2 * kL2;
    const double h = kM2 * kL1 * kL2 * s2;
    const Eigen::Vector2d c(-h * (2 * qd(0) * qd(1) + qd(1) * qd(1)), h * qd(0) * qd(0));
    const Eigen::Vector2d tau = mm * qdd + c + g;
    EXPECT_TRUE(model_.inverse_dynamics(data_, q, qd, qdd).isApprox(tau, 1e-6));
    EXPECT_TRUE(model_.mass_matrix(data_, q).isApprox(mm, 1e-6));
  }
}

TEST(KinematicsModel, JacobianMatchesFiniteDifferences) {
  const Model m = mobile_drill(true);
  Data d = m.make_data();
  std::mt19937 rng(3);
  constexpr double kEps = 1e-6;
  for (const std::string frame : {"tcp", "wheel_rl", "arm_link_3"}) {
    for (int k = 0; k < 5; ++k) {
      const Eigen::VectorXd q = random_q(m, rng);
      const Eigen::MatrixXd jac = m.frame_jacobian(d, q, frame);
      ASSERT_EQ(jac.rows(), 6);
      ASSERT_EQ(jac.cols(), m.dof());
      const Eigen::Isometry3d x0 = m.frame_pose(d, q, frame);
      for (int j = 0; j < m.dof(); ++j) {
        Eigen::VectorXd qp = q;
        qp(j) += kEps;
        const Eigen::Isometry3d x1 = m.frame_pose(d, qp, frame);
        const Eigen::Vector3d v = (x1.translation() - x0.translation()) / kEps;
        const Eigen::Vector3d w = rotation_difference(x1.linear(), x0.linear()) / kEps;
        EXPECT_LT((jac.block<3, 1>(0, j) - v).norm(), 1e-5) << frame << " joint " << m.joint_names()[j];
        EXPECT_LT((jac.block<3, 1>(3, j) - w).norm(), 1e-5) << frame << " joint " << m.joint_names()[j];
      }
    }
  }
}

TEST(KinematicsModel, ExternalWrenchEntersAsJacobianTranspose) {
  // Static RNE with a wrench f applied on the robot at the tcp: tau = g(q) - J(q)^T f.
  const Model m = mobile_drill(false);
  Data d = m.make_data();
  std::mt19937 rng(5);
  const Eigen::VectorXd q = random_q(m, rng);
  Eigen::Matrix<double, 6, 1> f;
  f << 3.0, -2.0, 10.0, 0.5, -0.3, 0.2;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m.dof());
  const Eigen::VectorXd tau = m.inverse_dynamics(d, q, zero, zero, {{"tcp", f}});
  const Eigen::VectorXd expected = m.gravity_torques(d, q) - m.frame_jacobian(d, q, "tcp").transpose() * f;
  EXPECT_TRUE(tau.isApprox(expected, 1e-9));
}

TEST(KinematicsModel, PlanarBaseVirtualJoints) {
  const Model m = mobile_drill(true);
  ASSERT_EQ(m.dof(), 17);
  EXPECT_EQ(m.num_virtual_joints(), 3);
  EXPECT_EQ(m.joint_names()[0], "base_x");
  EXPECT_EQ(m.joint_names()[1], "base_y");
  EXPECT_EQ(m.joint_names()[2], "base_yaw");
  EXPECT_TRUE(m.is_virtual_joint(2));
  EXPECT_FALSE(m.is_virtual_joint(3));
  EXPECT_FALSE(m.joint_limits()[0].has_position_limits);
  Data d = m.make_data();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.dof());
  const Eigen::Vector3d tcp0 = m.frame_pose(d, q, "tcp").translation();
  q(0) = 1.0;
  q(1) = -2.0;
  q(2) = M_PI / 2;
  const Eigen::Vector3d tcp1 = m.frame_pose(d, q, "tcp").translation();
  EXPECT_TRUE(tcp1.isApprox(Eigen::Vector3d(1.0 - tcp0.y(), -2.0 + tcp0.x(), tcp0.z()), 1e-12));
  const Eigen::VectorXd g = m.gravity_torques(d, q);
  EXPECT_NEAR(g(0), 0.0, 1e-9);
  EXPECT_NEAR(g(1), 0.0, 1e-9);
  EXPECT_NEAR(g(2), 0.0, 1e-9);
  // Same arm gravity torques as the fixed-base model (yaw does not change them).
  const Model fixed = mobile_drill(false);
  Data fd = fixed.make_data();
  EXPECT_TRUE(g.tail(fixed.dof()).isApprox(fixed.gravity_torques(fd, q.tail(fixed.dof())), 1e-9));
}

TEST(KinematicsModel, MassMatrixSymmetricPositiveDefinite) {
  const Model m = mobile_drill(true);
  Data d = m.make_data();
  std::mt19937 rng(9);
  const Eigen::MatrixXd mm = m.mass_matrix(d, random_q(m, rng));
  EXPECT_TRUE(mm.isApprox(mm.transpose(), 1e-9));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(mm);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  // Translating the whole robot: the generalized mass of base_x is the total mass.
  EXPECT_NEAR(mm(0, 0), m.total_mass(), 1e-9);
}

TEST(KinematicsModel, DataPerThreadGivesSameResults) {
  const Model m = mobile_drill(true);
  std::mt19937 rng(1);
  std::vector<Eigen::VectorXd> qs;
  for (int i = 0; i < 50; ++i) {
    qs.push_back(random_q(m, rng));
  }
  Data d = m.make_data();
  std::vector<Eigen::Vector3d> expected;
  for (const auto& q : qs) {
    expected.push_back(m.frame_pose(d, q, "tcp").translation());
  }
  std::vector<int> mismatches(2, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t) {
    threads.emplace_back([&, t] {
      Data local = m.make_data();
      for (std::size_t i = 0; i < qs.size(); ++i) {
        if (!m.frame_pose(local, qs[i], "tcp").translation().isApprox(expected[i], 1e-12)) {
          ++mismatches[t];
        }
        (void)m.gravity_torques(local, qs[i]);
      }
    });
  }
  for (auto& t : threads) {
    t.join();
  }
  EXPECT_EQ(mismatches[0] + mismatches[1], 0);
}

TEST(KinematicsModel, InverseKinematicsReachesPosesFromFk) {
  const Model m = mobile_drill(false);
  Data d = m.make_data();
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  IkOptions options;
  for (const std::string j : {"J1_A", "J2_A", "J3_A", "J4_B", "J5_B", "J6_B"}) {
    options.joints.push_back(m.joint_index_or_throw(j));
  }
  int converged = 0;
  for (int k = 0; k < 20; ++k) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(m.dof());
    for (int j : options.joints) {
      q(j) = u(rng);
    }
    const Eigen::Isometry3d target = m.frame_pose(d, q, "tcp");
    Eigen::VectorXd seed = q;
    for (int j : options.joints) {
      seed(j) += 0.3 * u(rng);
    }
    const IkResult r = m.inverse_kinematics(d, "tcp", target, seed, options);
    if (r.converged) {
      ++converged;
      const Eigen::Isometry3d reached = m.frame_pose(d, r.q, "tcp");
      EXPECT_LT((reached.translation() - target.translation()).norm(), 1e-6);
      EXPECT_LT(rotation_difference(reached.linear(), target.linear()).norm(), 1e-6);
      for (int j = 0; j < m.dof(); ++j) {
        if (std::find(options.joints.begin(), options.joints.end(), j) == options.joints.end()) {
          EXPECT_EQ(r.q(j), 0.0);  // legs untouched
        }
      }
    }
  }
  EXPECT_GE(converged, 18);
  // Out of reach: not converged, error reported.
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 5.0, 0.0, 1.0;
  const IkResult r = m.inverse_kinematics(d, "tcp", far, Eigen::VectorXd::Zero(m.dof()), options);
  EXPECT_FALSE(r.converged);
  EXPECT_GT(r.position_error, 2.0);
  // Default joint set: the chain moving the frame (arm joints, not the legs).
  options.joints.clear();
  options.position_only = true;
  Eigen::Isometry3d near = m.frame_pose(d, Eigen::VectorXd::Zero(m.dof()), "tcp");
  near.translation() += Eigen::Vector3d(0.1, 0.1, -0.2);
  const IkResult p = m.inverse_kinematics(d, "tcp", near, Eigen::VectorXd::Zero(m.dof()), options);
  EXPECT_TRUE(p.converged);
  EXPECT_EQ(p.q(m.joint_index_or_throw("J_wheel_fl")), 0.0);
}

// A robot of passive modules only (no moving joint): KDL's solvers cannot be used (they read
// q(0) of an empty q); poses compose the fixed joints, the Jacobian has no column, no torque.
TEST(KinematicsModel, NoMovingJoint) {
  const Model m = Model::from_urdf_string(R"(<robot name="passive">
    <link name="base_link"/>
    <link name="post"><inertial><mass value="2"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
    <link name="tip"/>
    <joint name="fixed_post" type="fixed"><parent link="base_link"/><child link="post"/>
      <origin xyz="0.1 0 0.3" rpy="0 0 1.5707963267948966"/></joint>
    <joint name="fixed_tip" type="fixed"><parent link="post"/><child link="tip"/>
      <origin xyz="0.2 0 0" rpy="0 0 0"/></joint>
  </robot>)");
  ASSERT_EQ(m.dof(), 0);
  Data d = m.make_data();
  const Eigen::VectorXd q(0);
  const Eigen::Isometry3d tip = m.frame_pose(d, q, "tip");
  EXPECT_TRUE(tip.translation().isApprox(Eigen::Vector3d(0.1, 0.2, 0.3), 1e-12))
      << tip.translation().transpose();
  EXPECT_TRUE(m.frame_pose(d, q, "world").isApprox(Eigen::Isometry3d::Identity()));
  Eigen::Isometry3d into;
  m.frame_pose_into(d, q, "tip", into);
  EXPECT_TRUE(into.isApprox(tip));
  const Eigen::MatrixXd jac = m.frame_jacobian(d, q, "tip");
  EXPECT_EQ(jac.rows(), 6);
  EXPECT_EQ(jac.cols(), 0);
  EXPECT_EQ(m.gravity_torques(d, q).size(), 0);
  EXPECT_EQ(m.inverse_dynamics(d, q, q, q, {{"tip", Eigen::Matrix<double, 6, 1>::Ones()}}).size(),
            0);
}

TEST(KinematicsModel, ClearErrors) {
  EXPECT_THROW(Model::from_urdf_string("<robot name='x'><link name='a'/>"), ModelError);
  // A character cut short at the end made the XML parser read past the text (found by
  // tests/fuzz): refused before parsing.
  try {
    (void)Model::from_urdf_string("<robot name='x'><link name='a\xf0'/></robot>");
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()), "URDF is not valid UTF-8 (byte 29)");
  }
  try {
    (void)Model::from_urdf_file("/nonexistent/robot.urdf");
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.urdf"), std::string::npos);
  }
  const Model m = two_link();
  Data d = m.make_data();
  try {
    (void)m.frame_pose(d, Eigen::VectorXd::Zero(2), "flange");
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("flange"), std::string::npos);
  }
  try {
    (void)m.gravity_torques(d, Eigen::VectorXd::Zero(3));
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("size 3"), std::string::npos);
  }
  try {
    (void)m.joint_index_or_throw("elbow");
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("elbow"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("j1, j2"), std::string::npos);
  }
}

}  // namespace
}  // namespace concert::kinematics
