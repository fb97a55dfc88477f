// PlanningModel and StateChecker on the paper's morphologies: configuration space, FK against
// orocos-kdl, base on the floor, each constraint rejecting what it should.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <random>

#include "concert/model/limits.hpp"
#include "planner/state_checker.hpp"
#include "planner/fixtures.hpp"
#include "planner/trajectory.hpp"

using namespace concert::planner;
namespace model = concert::model;
namespace kinematics = concert::kinematics;

namespace {

std::shared_ptr<const PlanningModel> morphology(char which, const Params& params = {}) {
  return PlanningModel::build(fixtures::model_from_assembly(fixtures::data_dir() / (std::string("morphology_") + which + ".yaml"), 1),
                              params);
}

}  // namespace

TEST(PlanningModel, ConfigurationSpaceIsBasePlusArm) {
  for (char which : {'a', 'b'}) {
    const auto m = morphology(which);
    ASSERT_EQ(m->dof(), 9) << which;  // x, y, yaw + 6 arm joints
    EXPECT_EQ(m->joint_names()[0], "base_x");
    EXPECT_EQ(m->joint_names()[3], "J1_E");
    EXPECT_EQ(m->joint_names()[8], "J6_E");
    EXPECT_GT(m->full_dof(), m->dof());  // legs are in the model but not planned
    EXPECT_NEAR(m->torque_limits()[m->kinematics().joint_index_or_throw("J2_E")], 160.0, 1e-9);  // Large A continuous
    EXPECT_NEAR(m->torque_limits()[m->kinematics().joint_index_or_throw("J6_E")], 120.0, 1e-9);  // Large B continuous
    EXPECT_TRUE(m->ignored_shapes().empty());
  }
}

TEST(PlanningModel, LinkPosesAgreeWithKdl) {
  const auto m = morphology('b');
  concert::kinematics::Data data = m->kinematics().make_data();
  std::mt19937 rng(5u);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<Eigen::Isometry3d> poses;
  for (int s = 0; s < 20; ++s) {
    Eigen::VectorXd q(m->full_dof());
    for (Eigen::Index i = 0; i < q.size(); ++i) q[i] = u(rng);
    m->link_poses(q, poses);
    for (std::size_t l = 0; l < m->links().size(); ++l) {
      Eigen::Isometry3d kdl = m->kinematics().frame_pose(data, q, m->links()[l].name);
      kdl.translation().z() += m->base_height();
      EXPECT_LT((kdl.translation() - poses[l].translation()).norm(), 1e-9) << m->links()[l].name;
      EXPECT_LT((kdl.linear() - poses[l].linear()).norm(), 1e-9) << m->links()[l].name;
    }
  }
}

TEST(PlanningModel, StaticTorquesAgreeWithKdl) {
  // The one-pass static torques (gravity + a contact force) equal orocos-kdl's recursive
  // Newton-Euler gravity torques minus J^T f, on random postures of both morphologies.
  for (const char which : {'a', 'b'}) {
    const auto m = morphology(which);
    const concert::kinematics::Model& k = m->kinematics();
    concert::kinematics::Data data = k.make_data();
    std::mt19937 rng(11u);
    std::uniform_real_distribution<double> u(-2.5, 2.5);
    std::vector<Eigen::Isometry3d> poses;
    Eigen::VectorXd tau;
    const int tool = m->link_index("tcp_E");
    ASSERT_GE(tool, 0);
    for (int s = 0; s < 20; ++s) {
      Eigen::VectorXd q(m->full_dof());
      for (Eigen::Index i = 0; i < q.size(); ++i) q[i] = u(rng);
      const Eigen::Vector3d force(u(rng) * 100.0, u(rng) * 100.0, u(rng) * 100.0);
      m->link_poses(q, poses);
      m->static_torques(poses, -1, Eigen::Vector3d::Zero(), tau);
      const Eigen::VectorXd gravity = k.gravity_torques(data, q);
      EXPECT_LT((tau - gravity).cwiseAbs().maxCoeff(), 1e-7) << which << " sample " << s;
      m->static_torques(poses, tool, force, tau);
      const Eigen::VectorXd with_force = gravity - k.frame_jacobian(data, q, "tcp_E").topRows<3>().transpose() * force;
      // The virtual base joints carry no torque in static_torques (the floor holds the base).
      const Eigen::Index joints = q.size() - 3;
      EXPECT_LT((tau - with_force).tail(joints).cwiseAbs().maxCoeff(), 1e-7) << which << " sample " << s;
      EXPECT_EQ(tau.head<3>().norm(), 0.0);
      EXPECT_GT(gravity.cwiseAbs().maxCoeff(), 1.0);  // not trivially zero
    }
  }
}

TEST(PlanningModel, BaseStandsOnTheFloorAndArmGrowsWithMorphology) {
  const auto a = morphology('a');
  const auto b = morphology('b');
  EXPECT_GT(a->base_height(), 0.3);
  EXPECT_LT(a->base_height(), 1.0);
  EXPECT_NEAR(a->base_height(), b->base_height(), 1e-12);
  // Arm straight up: B's tool is 0.4 m higher (the second passive link).
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(a->full_dof());
  const double za = a->link_pose(q, "tcp_E").translation().z();
  const double zb = b->link_pose(Eigen::VectorXd::Zero(b->full_dof()), "tcp_E").translation().z();
  EXPECT_NEAR(zb - za, 0.4, 1e-6);
}

TEST(PlanningModel, ToolAndCameraFrames) {
  const auto m = morphology('a');
  EXPECT_EQ(m->tool("").name, "drill_E");
  EXPECT_EQ(m->tool("").kind, model::EndEffectorKind::kDrill);  // by role: the wheels come first
  EXPECT_EQ(m->description().end_effectors.front().kind, model::EndEffectorKind::kWheel);
  EXPECT_EQ(m->camera_frame(m->tool("drill_E")), "camera_E");
  try {
    (void)m->camera_frame(m->tool("wheel_A"));
    FAIL() << "a wheel has no camera";
  } catch (const PlannerError& e) {
    EXPECT_NE(std::string(e.what()).find("'wheel_A' has no camera sensor"), std::string::npos) << e.what();
  }
  try {
    (void)m->tool("sander_E");
    FAIL() << "unknown end-effector accepted";
  } catch (const PlannerError& e) {
    EXPECT_NE(std::string(e.what()).find("drill_E"), std::string::npos) << e.what();
  }
}

TEST(PlanningModel, MirroredArmReflectsTheCamera) {
  // The image about the vertical plane through the first arm joint: the camera at the same
  // height and distance from that joint's axis, its optical axis at the same elevation. On A
  // and on C (the arm on the Passive Base Link).
  for (const char which : {'a', 'c'}) {
    const auto m = morphology(which);
    const std::string camera = m->camera_frame(m->tool(""));
    std::string first_joint_link;
    for (const LinkNode& l : m->links()) {
      if (l.full_index == m->planned_indices()[3]) {
        first_joint_link = l.name;
        break;
      }
    }
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m->full_dof());
    const Eigen::Isometry3d j1 = m->link_pose(zero, first_joint_link);
    const Eigen::Vector3d up = j1.linear() * m->links()[static_cast<std::size_t>(m->link_index(first_joint_link))].axis;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int images = 0;
    for (int k = 0; k < 50; ++k) {
      Eigen::VectorXd q = Eigen::VectorXd::Zero(m->dof());
      for (int i = 3; i < m->dof(); ++i) q[i] = m->lower()[i] + (m->upper()[i] - m->lower()[i]) * unit(rng);
      const std::optional<Eigen::VectorXd> image = m->mirrored_arm(q.tail(m->dof() - 3));
      if (!image) continue;
      images += 1;
      const std::optional<Eigen::VectorXd> back = m->mirrored_arm(*image);
      ASSERT_TRUE(back.has_value());
      EXPECT_TRUE(back->isApprox(q.tail(m->dof() - 3), 1e-12));
      Eigen::VectorXd qm = q;
      qm.tail(m->dof() - 3) = *image;
      const Eigen::Isometry3d c1 = m->link_pose(m->to_full(q, zero), camera);
      const Eigen::Isometry3d c2 = m->link_pose(m->to_full(qm, zero), camera);
      const auto off_axis = [&](const Eigen::Vector3d& p) {
        const Eigen::Vector3d d = p - j1.translation();
        return (d - d.dot(up) * up).norm();
      };
      EXPECT_NEAR(c1.translation().dot(up), c2.translation().dot(up), 1e-9) << which;
      EXPECT_NEAR(off_axis(c1.translation()), off_axis(c2.translation()), 1e-9) << which;
      EXPECT_NEAR(c1.linear().col(2).dot(up), c2.linear().col(2).dot(up), 1e-9) << which;
      EXPECT_GT((c1.translation() - c2.translation()).norm() + (*image - q.tail(m->dof() - 3)).norm(), 0.0);
    }
    EXPECT_GE(images, 40) << which << ": the joint limits are nearly symmetric, most postures have an image";
  }
  // An oblique joint axis (tilted 30 degrees out of both planes): no mirror image.
  ModelDescription d = fixtures::model_from_assembly(fixtures::data_dir() / "morphology_a.yaml", 1);
  std::string arm_joint;
  for (const model::ChainInfo& c : d.chains) {
    if (c.role == model::ChainRole::kArm) arm_joint = c.joints.at(1);
  }
  const std::size_t at = d.urdf.find("<joint name=\"" + arm_joint + "\"");
  ASSERT_NE(at, std::string::npos);
  const std::size_t axis = d.urdf.find("<axis", at);
  const std::size_t end = d.urdf.find("/>", axis);
  d.urdf.replace(axis, end + 2 - axis, "<axis xyz=\"0.5 0.5 0.7071068\"/>");
  const auto oblique = PlanningModel::build(d, {});
  EXPECT_FALSE(oblique->mirrored_arm(Eigen::VectorXd::Zero(oblique->dof() - 3)).has_value());
  EXPECT_TRUE(morphology('a')->mirrored_arm(Eigen::VectorXd::Zero(oblique->dof() - 3)).has_value());
}

TEST(PlanningModel, BadModelsNameTheProblem) {
  ModelDescription d = fixtures::model_from_assembly(fixtures::data_dir() / "morphology_a.yaml", 3);
  ModelDescription no_arm = d;
  for (model::ChainInfo& c : no_arm.chains) {
    if (c.role == model::ChainRole::kArm) c.role = model::ChainRole::kOther;
  }
  EXPECT_THROW((void)PlanningModel::build(no_arm, {}), PlannerError);
  ModelDescription bad_srdf = d;
  bad_srdf.srdf = "<robot><disable_collisions link1=\"nope\" link2=\"base_link\"/></robot>";
  try {
    (void)PlanningModel::build(bad_srdf, {});
    FAIL();
  } catch (const PlannerError& e) {
    EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos) << e.what();
  }
  ModelDescription bad_urdf = d;
  bad_urdf.urdf = "<robot";
  EXPECT_THROW((void)PlanningModel::build(bad_urdf, {}), PlannerError);
}

// The module database gives the drill's body, whose shapes end behind its TCP: the planner adds
// the bit, a cylinder from the TCP back to them. A wall the bit's tip goes into, the body clear
// of it, is a collision; without the bit (drill_bit_radius 0) it was not.
TEST(PlanningModel, TheDrillsBitIsACylinderFromTheTcpBackToTheDrillsBody) {
  Params with_bit;
  with_bit.drill_bit_radius = 0.008;
  const auto m = morphology('a', with_bit);
  // The drill's TCP link of a model; end() when it has none.
  const auto tcp_of = [](const PlanningModel& model) {
    return std::find_if(model.links().begin(), model.links().end(),
                        [&](const LinkNode& l) { return l.name == model.tool("").frame; });
  };
  const auto tcp = tcp_of(*m);
  ASSERT_NE(tcp, m->links().end());
  ASSERT_EQ(tcp->shapes.size(), 1u);
  const LinkShape& bit = tcp->shapes.front();
  EXPECT_EQ(bit.type, LinkShape::Type::kCylinder);
  EXPECT_DOUBLE_EQ(bit.size.x(), with_bit.drill_bit_radius);
  // The CONCERT drill's box ends 0.105 m behind its TCP (module database, concert_drill).
  EXPECT_NEAR(bit.size.z(), 0.105, 0.01);
  EXPECT_NEAR(bit.origin.translation().z(), -0.5 * bit.size.z(), 1e-12);
  Params no_bit;
  no_bit.drill_bit_radius = 0.0;
  const auto bare = morphology('a', no_bit);
  const auto bare_tcp = tcp_of(*bare);
  ASSERT_NE(bare_tcp, bare->links().end());
  EXPECT_TRUE(bare_tcp->shapes.empty());

  // A plate across the bit's tip, 4 cm deep along the tool's axis, the drill's body behind it.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m->full_dof());
  std::vector<Eigen::Isometry3d> poses;
  m->link_poses(q, poses);
  const Eigen::Isometry3d at = poses[static_cast<std::size_t>(tcp - m->links().begin())];
  // World boxes turn about z only: the tool's axis is horizontal at q = 0, the plate upright
  // across it, 4 cm thick along it.
  const Eigen::Vector3d axis = at.linear().col(2);
  ASSERT_LT(std::abs(axis.z()), 0.01);
  World world;
  world.boxes.push_back({"plate", Eigen::Vector3d(0.04, 0.2, 0.2), at * Eigen::Vector3d(0.0, 0.0, -0.025),
                         std::atan2(axis.y(), axis.x())});
  Environment env(0.01);
  env.add_world(world);
  const Validity hit = StateChecker(m, env, with_bit, 0.0).check(q);
  EXPECT_EQ(hit.constraint, Constraint::kEnvironmentCollision) << hit.detail;
  const Validity without = StateChecker(bare, env, no_bit, 0.0).check(q);
  EXPECT_NE(without.constraint, Constraint::kEnvironmentCollision) << without.detail;
}

TEST(StateChecker, EachConstraintRejects) {
  const Params params;
  const auto m = morphology('a');
  Environment env(0.05);
  World world;
  world.boxes.push_back(fixtures::wall_at(1.5));
  env.add_world(world);
  EXPECT_TRUE(env.occupied({1.55, 0.0, 1.0}));
  EXPECT_FALSE(env.occupied({1.2, 0.0, 1.0}));
  StateChecker checker(m, env, params, 0.0);
  const auto& k = m->kinematics();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m->full_dof());
  // Arm straight up, robot at the origin: valid.
  const Validity home = checker.check(q);
  EXPECT_TRUE(home.valid()) << to_string(home.constraint) << ": " << home.detail;

  Eigen::VectorXd over = q;
  over[k.joint_index_or_throw("J2_E")] = 3.0;
  EXPECT_EQ(checker.check(over).constraint, Constraint::kJointLimit);

  // Arm horizontal: gravity alone exceeds the shoulder's continuous torque.
  Eigen::VectorXd flat = q;
  flat[k.joint_index_or_throw("J2_E")] = M_PI / 2;
  const Validity torque = checker.check(flat);
  EXPECT_EQ(torque.constraint, Constraint::kTorqueLimit) << torque.detail;
  EXPECT_NE(torque.detail.find("J2_E"), std::string::npos) << torque.detail;

  // Base driven into the wall.
  Eigen::VectorXd into_wall = q;
  into_wall[0] = 1.2;
  EXPECT_EQ(checker.check(into_wall).constraint, Constraint::kEnvironmentCollision);

  // Elbow folded back onto the arm: self collision.
  Eigen::VectorXd folded_back = q;
  folded_back[k.joint_index_or_throw("J4_E")] = 2.75;
  folded_back[k.joint_index_or_throw("J6_E")] = 2.75;
  const Validity self = checker.check(folded_back);
  EXPECT_TRUE(self.constraint == Constraint::kSelfCollision || self.constraint == Constraint::kFloor) << self.detail;

  // The contact force of drilling adds torque: the same posture can pass without it and fail with it.
  const Eigen::VectorXd g = checker.required_torques(q, "");
  const Eigen::VectorXd gc = checker.required_torques(q, "tcp_E");
  EXPECT_GT((gc - g).norm(), 50.0);
}

TEST(Trajectory, TimingRespectsLimitsAndPassesThroughWaypoints) {
  const auto m = morphology('a');
  const Params params;
  const MotionLimits lim = motion_limits(*m, params);
  std::vector<Eigen::VectorXd> wp;
  std::mt19937 rng(3u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 4; ++i) {
    Eigen::VectorXd q(m->dof());
    for (Eigen::Index j = 0; j < q.size(); ++j) q[j] = u(rng);
    wp.push_back(q);
  }
  const Trajectory t = time_parameterize(wp, m->joint_names(), lim, 0.005);
  ASSERT_GT(t.points.size(), 10u);
  EXPECT_LT((t.points.front().q - wp.front()).norm(), 1e-12);
  EXPECT_LT((t.points.back().q - wp.back()).norm(), 1e-12);
  for (std::size_t i = 1; i < t.points.size(); ++i) {
    const double dt = t.points[i].time - t.points[i - 1].time;
    ASSERT_GT(dt, 0.0);
    const Eigen::VectorXd v = (t.points[i].q - t.points[i - 1].q) / dt;
    EXPECT_TRUE((v.cwiseAbs().array() <= lim.velocity.array() * 1.0001).all()) << "sample " << i;
    EXPECT_TRUE((t.points[i].qd.cwiseAbs().array() <= lim.velocity.array() * 1.0001).all()) << "sample " << i;
    const Eigen::VectorXd acc = (t.points[i].qd - t.points[i - 1].qd) / dt;
    EXPECT_TRUE((acc.cwiseAbs().array() <= lim.acceleration.array() * 1.0001).all()) << "sample " << i;
  }
  EXPECT_THROW((void)time_parameterize({}, m->joint_names(), lim, 0.01), PlannerError);
}

// The arm drives' thermal RMS and peak along a timed trajectory, judged from its samples alone
// (accelerations by finite differences of the sampled velocities, inverse dynamics on the planar
// model, model::ThermalLoad warm from the start posture): largest RMS / continuous, largest
// static load / continuous over the samples.
struct SampledLoads {
  double rms_share = 0.0, static_share = 0.0;
};
SampledLoads sampled_loads(const PlanningModel& m, const Trajectory& t, const Eigen::VectorXd& q_full) {
  const kinematics::Model& k = m.kinematics();
  kinematics::Data data = k.make_data();
  const auto& planned = m.planned_indices();
  const auto full = [&](const Eigen::VectorXd& part) {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(k.dof());
    out.head(q_full.size()) = q_full;
    for (std::size_t p = 0; p < planned.size(); ++p) out[planned[p]] = part[static_cast<Eigen::Index>(p)];
    return out;
  };
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(k.dof());
  std::vector<model::ThermalLoad> heat(planned.size());
  const Eigen::VectorXd g0 = k.gravity_torques(data, full(t.points.front().q));
  for (std::size_t p = 3; p < planned.size(); ++p) heat[p].hold(std::abs(g0[planned[p]]));
  SampledLoads out;
  for (std::size_t i = 1; i < t.points.size(); ++i) {
    const double dt = t.points[i].time - t.points[i - 1].time;
    Eigen::VectorXd qd = zero, qdd = zero;
    for (std::size_t p = 0; p < planned.size(); ++p) {
      qd[planned[p]] = t.points[i].qd[static_cast<Eigen::Index>(p)];
      qdd[planned[p]] = (t.points[i].qd - t.points[i - 1].qd)[static_cast<Eigen::Index>(p)] / dt;
    }
    const Eigen::VectorXd q = full(t.points[i].q);
    const Eigen::VectorXd tau = k.inverse_dynamics(data, q, qd, qdd);
    const Eigen::VectorXd g = k.gravity_torques(data, q);
    for (std::size_t p = 3; p < planned.size(); ++p) {
      const double c = m.robot().limits().at(m.joint_names()[p]).continuous_torque;
      out.rms_share = std::max(out.rms_share, heat[p].add(std::abs(tau[planned[p]]), dt) / c);
      out.static_share = std::max(out.static_share, std::abs(g[planned[p]]) / c);
    }
  }
  return out;
}

// A fast path (joint accelerations of 10 rad/s^2 at full joint speed) asks the arm drives for
// more than holding the path's postures does. Timed for the drives, its segments are stretched
// until the RMS over the thermal window, judged from the samples, stays within the fraction; a
// fraction below what holding the postures alone needs is refused (not sustainable).
TEST(Trajectory, SlowsDownWhereTheArmsDrivesCannotSustainTheKinematicLimits) {
  const auto m = morphology('a');
  Params params;
  params.velocity_scale = 1.0;
  params.joint_acceleration = 10.0;
  const MotionLimits lim = motion_limits(*m, params);
  std::vector<Eigen::VectorXd> wp;
  std::mt19937 rng(3u);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int i = 0; i < 4; ++i) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(m->dof());
    for (Eigen::Index j = 3; j < q.size(); ++j) q[j] = u(rng);
    wp.push_back(q);
  }
  const Eigen::VectorXd start = Eigen::VectorXd::Zero(m->full_dof());
  const Trajectory fast = time_parameterize(wp, m->joint_names(), lim, 0.005);
  const SampledLoads kinematic = sampled_loads(*m, fast, start);
  std::printf("kinematic timing: %.2f s, RMS %.0f %%, static %.0f %% of continuous\n", fast.points.back().time,
              100.0 * kinematic.rms_share, 100.0 * kinematic.static_share);
  ASSERT_GT(kinematic.rms_share, kinematic.static_share + 0.02) << "the path asks nothing of the drives' dynamics";

  DriveLimits drives;
  drives.model = m.get();
  drives.q_start_full = start;
  drives.fraction = std::min(1.0, kinematic.static_share + 0.5 * (kinematic.rms_share - kinematic.static_share));
  drives.max_stretch = 50.0;
  drives.max_stretches = 400;
  DriveReport report;
  const Trajectory fitted = time_parameterize(wp, m->joint_names(), lim, 0.005, drives, &report);
  std::printf("for %.0f %%: %s\n", 100.0 * drives.fraction, report.summary().c_str());
  EXPECT_TRUE(report.within) << report.summary();
  EXPECT_GT(report.stretches, 0);
  EXPECT_GT(fitted.points.back().time, fast.points.back().time);
  EXPECT_NEAR(report.slowed * fast.points.back().time, fitted.points.back().time, 1e-6);
  EXPECT_LT((fitted.points.back().q - wp.back()).norm(), 1e-12);
  const SampledLoads judged = sampled_loads(*m, fitted, start);
  EXPECT_LE(judged.rms_share, drives.fraction + 0.01);  // finite differences smear the switches

  drives.fraction = 0.9 * kinematic.static_share;  // less than holding the postures needs
  DriveReport refused;
  (void)time_parameterize(wp, m->joint_names(), lim, 0.005, drives, &refused);
  EXPECT_FALSE(refused.within);
  EXPECT_NE(refused.summary().find("not sustainable"), std::string::npos) << refused.summary();
  drives.fraction = 1.5;
  EXPECT_THROW((void)time_parameterize(wp, m->joint_names(), lim, 0.005, drives), PlannerError);
}
