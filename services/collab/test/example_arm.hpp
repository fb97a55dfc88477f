#pragma once
// An analytic stand-in for the paper's 7-DoF transport arm (Straight A - Elbow A - Straight A -
// Elbow A - Straight B - 0.4 m passive link - Elbow B - Straight B, about 2 m), for the MPC's
// tests and benchmark: forward kinematics in the base frame and a finite-difference Jacobian.
// The service itself takes the arm from the RobotModel (libs/kinematics).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

#include "collab/follow_me_mpc.hpp"
#include "collab/obstacle_map.hpp"

namespace concert::collab::test {

struct ExampleArm {
  static constexpr int kJoints = 7;
  // Joint axes (in the previous link's frame) and the link after each joint.
  std::array<Eigen::Vector3d, kJoints> axes{Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitY(),
                                            Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                            Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                            Eigen::Vector3d::UnitX()};
  std::array<Eigen::Vector3d, kJoints> links{Eigen::Vector3d(0, 0, 0.25), Eigen::Vector3d(0.45, 0, 0),
                                             Eigen::Vector3d(0.15, 0, 0), Eigen::Vector3d(0.45, 0, 0),
                                             Eigen::Vector3d(0.55, 0, 0), Eigen::Vector3d(0.1, 0, 0),
                                             Eigen::Vector3d(0.15, 0, 0)};
  Eigen::Vector3d mount{0.35, 0.0, 0.55};  // first joint on the base

  Eigen::Vector3d fk(const Eigen::VectorXd& q) const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = mount;
    for (int i = 0; i < kJoints; ++i) {
      T.rotate(Eigen::AngleAxisd(q[i], axes[static_cast<std::size_t>(i)]));
      T.translate(links[static_cast<std::size_t>(i)]);
    }
    return T.translation();
  }

  Eigen::MatrixXd jacobian(const Eigen::VectorXd& q) const {
    Eigen::MatrixXd J(3, kJoints);
    const double h = 1e-6;
    for (int i = 0; i < kJoints; ++i) {
      Eigen::VectorXd a = q, b = q;
      a[i] += h;
      b[i] -= h;
      J.col(i) = (fk(a) - fk(b)) / (2 * h);
    }
    return J;
  }

  // A carrying posture: the end-effector about 1.2 m ahead of the base centre, 0.8 m high.
  static Eigen::VectorXd posture() {
    Eigen::VectorXd q(kJoints);
    q << 0.0, 0.6, 0.0, 0.5, 0.0, -0.6, 0.0;
    return q;
  }

  static ArmLimits limits() {
    ArmLimits l;
    l.q_min = Eigen::VectorXd::Constant(kJoints, -2.5);
    l.q_max = Eigen::VectorXd::Constant(kJoints, 2.5);
    l.qd_max = Eigen::VectorXd::Constant(kJoints, 1.0);
    l.q_posture = posture();
    return l;
  }
};

/// A person holding the object: a spring-damper from the end-effector to the hand target.
inline Eigen::Vector3d person_force(const Eigen::Vector3d& hand, const Eigen::Vector3d& ee,
                                    const Eigen::Vector3d& ee_vel, double k = 150.0, double c = 30.0,
                                    double max = 150.0) {
  Eigen::Vector3d f = k * (hand - ee) - c * ee_vel;
  if (f.norm() > max) f *= max / f.norm();
  return f;
}


/// A closed-loop pull: the hand target starts `lead` ahead of the end-effector and walks along
/// +x at `speed`; the MPC runs every `period`; the robot integrates its commanded velocities
/// (kinematic). Pillars are seen by a lidar-like sampling of their outline into the grid.
struct PullRun {
  double min_clearance{std::numeric_limits<double>::infinity()};  ///< robot spheres to pillars [m]
  double base_travel{0.0};  ///< base x at the end [m]
  double peak_force{0.0};   ///< [N]
  double mean_lag{0.0};     ///< mean |hand - ee| in the plane [m]
  std::vector<double> solve_ms;
  std::vector<double> solve_cpu_ms;
  std::vector<int> iterations;
  int failures{0};
  int warm{0};
};

struct Pillar {
  Eigen::Vector2d centre;
  double radius;
};

inline PullRun pull(FollowMeMpc& mpc, const std::vector<RobotSphere>& spheres, const std::vector<Pillar>& pillars,
                    double seconds, double speed = 0.6, double period = 0.05) {
  const ExampleArm arm;
  PullRun run;
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  Eigen::VectorXd q = ExampleArm::posture();
  const auto ee_world = [&](const Eigen::Vector3d& b, const Eigen::VectorXd& qq) {
    const Eigen::Vector3d e = arm.fk(qq);
    const double c = std::cos(b.z()), s = std::sin(b.z());
    return Eigen::Vector3d(b.x() + c * e.x() - s * e.y(), b.y() + s * e.x() + c * e.y(), e.z());
  };
  Eigen::Vector3d ee = ee_world(base, q);
  Eigen::Vector3d hand = ee + Eigen::Vector3d(0.3, 0.0, 0.0);
  Eigen::Vector3d ee_vel = Eigen::Vector3d::Zero();
  GridParams gp;
  gp.resolution = 0.1;
  gp.sectors = 8;
  gp.max_range = 3.0;
  ObstacleGrid grid(gp);
  double lag_sum = 0;
  const int steps = static_cast<int>(seconds / period);
  for (int i = 0; i < steps; ++i) {
    hand.x() += speed * period;
    grid.reset(base.head<2>());
    for (const auto& p : pillars)
      for (int a = 0; a < 64; ++a) {
        const double t = 2 * 3.14159265358979 * a / 64;
        grid.add_point(p.centre + p.radius * Eigen::Vector2d(std::cos(t), std::sin(t)));
      }
    MpcInput in;
    in.base = base;
    in.q = q;
    in.ee_in_base = arm.fk(q);
    in.arm_jacobian = arm.jacobian(q);
    in.force = person_force(hand, ee, ee_vel);
    in.force.z() = 0.0;  // the person carries the object's height
    in.obstacles = grid.active(base.head<2>());
    in.period = period;
    run.peak_force = std::max(run.peak_force, in.force.norm());
    const MpcResult r = mpc.solve(in);
    if (!r.ok) {
      ++run.failures;
    } else {
      run.solve_ms.push_back(r.solve_ms);
      run.solve_cpu_ms.push_back(r.solve_cpu_ms);
      run.iterations.push_back(r.iterations);
      if (r.warm) ++run.warm;
      base += period * r.base_velocity;
      q += period * r.joint_velocity;
    }
    const Eigen::Vector3d ee_new = ee_world(base, q);
    ee_vel = (ee_new - ee) / period;
    ee = ee_new;
    lag_sum += (hand - ee).head<2>().norm();
    const double c = std::cos(base.z()), s = std::sin(base.z());
    for (const auto& sph : spheres) {
      const Eigen::Vector2d centre = base.head<2>() + Eigen::Vector2d(c * sph.offset.x() - s * sph.offset.y(),
                                                                       s * sph.offset.x() + c * sph.offset.y());
      for (const auto& p : pillars)
        run.min_clearance = std::min(run.min_clearance, (centre - p.centre).norm() - sph.radius - p.radius);
    }
  }
  run.base_travel = base.x();
  run.mean_lag = lag_sum / steps;
  return run;
}

}  // namespace concert::collab::test
