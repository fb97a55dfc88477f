// Sanding runs in the MuJoCo simulator (sim_run.hpp). The arm is driven as the robot service
// drives it for a Cartesian impedance command, and the force the law closes on is the robot
// service's estimate from the joint torques: both formulas are libs/kinematics' (impedance.hpp),
// with the robot service's constants.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>

#include "concert/kinematics/impedance.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/world/geometry.hpp"
#include "concert/world/world.hpp"
#include "sim_robot.hpp"
#include "surface_finish/sim_run.hpp"

namespace concert::surface_finish {

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// The plan's TCP position at plan time t (linear between samples) and its velocity.
struct PlanCursor {
  const std::vector<PathSample>* s;
  std::size_t k{0};
  void at(double t, Eigen::Vector3d& p, Eigen::Vector3d& v, const PathSample** sample) {
    const auto& ss = *s;
    while (k + 2 < ss.size() && ss[k + 1].t <= t) ++k;
    const PathSample& a = ss[k];
    const PathSample& b = ss[std::min(k + 1, ss.size() - 1)];
    const double dt = b.t - a.t;
    const double u = dt > 0.0 ? std::clamp((t - a.t) / dt, 0.0, 1.0) : 1.0;
    p = a.tcp.translation() + u * (b.tcp.translation() - a.tcp.translation());
    v = dt > 0.0 && t >= a.t && t <= b.t ? Eigen::Vector3d((b.tcp.translation() - a.tcp.translation()) / dt)
                                          : Eigen::Vector3d::Zero();
    *sample = &b;
  }
};

}  // namespace

SandRunResult run_sand_in_sim(const SandRunParams& params) {
  const auto wall_clock = std::chrono::steady_clock::now();
  if (params.module_dbs.empty()) throw FinishError("sand run: no module database");
  if (!(params.force > 0.0)) throw FinishError("sand run: the force setpoint must be positive");
  if (!(params.command_period >= 0.001) || !(params.stiffness > 0.0) || !(params.rot_stiffness > 0.0)) {
    throw FinishError("sand run: command period >= 1 ms and positive stiffnesses needed");
  }
  const world::World w = world::load_world_file(params.world.string());
  if (w.surfaces.empty()) throw FinishError("sand run: world file '" + params.world.string() + "' has no plaster surface to sand");
  const world::Surface& surface = w.surfaces.front();
  const Eigen::Isometry3d face = world::face_frame(world::find_wall(w, surface.wall), surface.face);

  const detail::SimRobot loaded = detail::load_sim_robot(params.assembly, params.module_dbs);
  const sim::SimulatedRobot& robot = loaded.robot;
  const auto& model = loaded.model;
  ReachParams rp;
  rp.contact_force = params.force;
  Reach reach(model, model::EndEffectorKind::kSanding, rp);
  SandRunResult result;

  // The disc's friction against the stroke (SandRunParams::disc_rpm): the running disc's
  // abrasive slides at the rim speed omega R; the stroke's velocity v tilts the sliding
  // directions by v / (omega r) at radius r, which averages to v / (omega R) over the disc.
  if (!(params.disc_rpm >= 0.0) || !(params.abrasive_friction >= 0.0) || !(params.tool.coat_width > 0.0)) {
    throw FinishError("sand run: disc speed, abrasive friction and disc width must be >= 0 (width > 0)");
  }
  const double omega_r = params.disc_rpm * 2.0 * M_PI / 60.0 * 0.5 * params.tool.coat_width;
  result.disc_friction =
      omega_r > 0.0 ? std::min(params.abrasive_friction, params.abrasive_friction * params.path.speed / omega_r)
                    : params.abrasive_friction;
  sim::SimParams sp;
  sp.sensors.enabled = false;
  {
    const kinematics::Model& km = model->kinematics();
    const std::vector<int>& arm_joints = reach.arm_joints();
    for (const std::string& link : km.subtree_links(arm_joints.back())) sp.link_friction[link] = result.disc_friction;
  }
  sim::SimHardware hw(robot.urdf, w, sp);
  const std::vector<std::string> names = hw.joint_names();
  const kinematics::Model& k = model->kinematics();
  const int dof = k.dof();
  std::vector<int> index(names.size(), -1);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (auto j = k.joint_index(names[i])) index[i] = *j;
  }
  const std::vector<int>& arm = reach.arm_joints();
  const auto na = static_cast<Eigen::Index>(arm.size());
  std::vector<bool> is_arm(static_cast<std::size_t>(dof), false);
  for (int j : arm) is_arm[static_cast<std::size_t>(j)] = true;
  // The links the world can push on: the last arm joint's subtree (the tool and its flange).
  const std::vector<std::string> tool_links = k.subtree_links(arm.back());
  const std::string& tcp_frame = reach.tcp_frame();

  hardware::HardwareState state;
  std::vector<hardware::DriveCommand> cmd(names.size());
  kinematics::Data data = k.make_data();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(dof), qd = Eigen::VectorXd::Zero(dof), tau = Eigen::VectorXd::Zero(dof);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(dof);
  Eigen::VectorXd g(dof), id(dof), residual(na), qd_arm(na), tau_arm(na);
  Eigen::MatrixXd jac(6, dof), jac_arm(6, na);
  Eigen::Isometry3d ee = Eigen::Isometry3d::Identity();
  Vector6d wrench = Vector6d::Zero();
  bool wrench_init = false;
  const double dt = 0.001;
  const double wrench_tau = 0.02;  // RobotParams::wrench_filter_time_constant
  auto read = [&] {
    hw.read(state);
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (index[i] < 0) continue;
      q[index[i]] = state.position[i];
      qd[index[i]] = state.velocity[i];
      tau[index[i]] = state.effort[i];
    }
    // The robot service's estimation (RobotCore::cycle): g(q), pose, Jacobian, wrench.
    k.inverse_dynamics_into(data, q, zero, zero, g);
    k.frame_pose_into(data, q, tcp_frame, ee);
    k.frame_jacobian_into(data, q, tcp_frame, jac);
    k.inverse_dynamics_into(data, q, qd, zero, id);
    for (Eigen::Index a = 0; a < na; ++a) {
      const int j = arm[static_cast<std::size_t>(a)];
      jac_arm.col(a) = jac.col(j);
      residual(a) = id(j) - tau(j);
      qd_arm(a) = qd(j);
    }
    const Vector6d raw = kinematics::wrench_from_residual(jac_arm, residual);
    wrench = wrench_init ? kinematics::low_pass(wrench, raw, dt, wrench_tau) : raw;
    wrench_init = true;
  };
  // Position mode with velocity feed-forward and gravity (the trajectory controller).
  auto drive_joints = [&](const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref) {
    detail::position_commands(index, q_ref, qd_ref, g, cmd);
    hw.write(cmd);
    hw.step(dt);
    read();
  };
  // Cartesian impedance of the TCP on the arm (CartesianController::update); the other joints hold.
  Vector6d kgain, dgain;
  const double zeta = params.damping_ratio;
  kgain << Eigen::Vector3d::Constant(params.stiffness), Eigen::Vector3d::Constant(params.rot_stiffness);
  dgain << Eigen::Vector3d::Constant(2.0 * zeta * std::sqrt(params.stiffness * 10.0)),
      Eigen::Vector3d::Constant(2.0 * zeta * std::sqrt(params.rot_stiffness * 0.5));
  const double nullspace_damping = 2.0;  // CartesianCommand::nullspace_damping
  double normal_k = params.normal_stiffness > 0.0 ? params.normal_stiffness : params.stiffness;
  const double normal_d = 2.0 * zeta * std::sqrt(normal_k * 10.0);
  Eigen::Vector3d z_ee = Eigen::Vector3d::UnitZ();  // into the wall (set once the plan is known)
  Eigen::VectorXd q_hold;
  auto drive_cartesian = [&](const Eigen::Isometry3d& target, const Eigen::Vector3d& target_velocity) {
    const Vector6d twist = jac_arm * qd_arm;
    Vector6d target_twist = Vector6d::Zero();
    target_twist.head<3>() = target_velocity;
    Vector6d f = kinematics::impedance_wrench(ee, target, twist, target_twist, kgain, dgain);
    // Softer along z_ee (normal_stiffness): bumps press less on the wall before the law reacts.
    const Eigen::Vector3d position_error = target.translation() - ee.translation();
    f.head<3>() += (normal_k - params.stiffness) * z_ee * z_ee.dot(position_error) +
                   (normal_d - dgain(0)) * z_ee * z_ee.dot(target_twist.head<3>() - twist.head<3>());
    kinematics::wrench_torques(jac_arm, f, qd_arm, nullspace_damping, tau_arm);
    for (std::size_t i = 0; i < names.size(); ++i) {
      cmd[i] = hardware::DriveCommand{};
      cmd[i].mode = hardware::DriveMode::kPosition;
      if (index[i] < 0) continue;
      const int j = index[i];
      if (is_arm[static_cast<std::size_t>(j)]) {
        const auto a = static_cast<Eigen::Index>(std::find(arm.begin(), arm.end(), j) - arm.begin());
        cmd[i].mode = hardware::DriveMode::kEffort;
        cmd[i].effort = tau_arm(a) + g[j];
      } else {
        cmd[i].position = q_hold[j];
        cmd[i].effort = g[j];
      }
    }
    hw.write(cmd);
    hw.step(dt);
    read();
  };

  read();
  q_hold = q;
  for (int i = 0; i < 500; ++i) drive_joints(q_hold, zero);

  // The panel's nominal surface in the base frame (the simulator's truth: the wall fit from the
  // scan is tested with the spraying runs).
  const Eigen::Isometry3d base0 = hw.base_pose();
  const Eigen::Isometry3d inv = base0.inverse();
  const Eigen::Vector3d n_world = face.linear().col(2);
  const Eigen::Vector3d p_world = face.translation() + surface.thickness * n_world;
  const WallFrame wall = WallFrame::from_plane(inv * p_world, inv.linear() * n_world, base0.translation().z());
  result.areas = compute_areas(reach, wall, Task::kSand, params.tool.standoff, params.areas);
  const Area& area = result.areas.area(params.area);
  result.rect = params.rect ? reshape(area, *params.rect) : area.rect;
  const auto strokes = serpentine_strokes(result.rect, params.tool, params.path.visible);
  result.plan = plan_serpentine(reach, wall, result.rect, params.tool, result.areas.roll, params.path, q,
                                &result.areas.posture_near(strokes.front().x, strokes.front().y_start));
  const SerpentinePlan& plan = result.plan;
  const auto& s = plan.samples;

  // Phases of the plan: the joint move (up to the approach pose), the approach (to the nominal
  // surface), the strokes and joins (in contact), the retreat.
  std::size_t i_app = 0, i_wall = 0, i_last = 0;
  const double off = params.tool.standoff;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (i_app == 0 && std::abs(s[i].wall.z() - (off + params.path.approach)) < 1e-6) i_app = i;
    if (s[i].stroke == 0 && i_wall == 0) i_wall = i - 1;
    if (s[i].stroke >= 0) i_last = i;
  }
  if (i_wall <= i_app || i_last <= i_wall) throw FinishError("sand run: the plan has no approach or no stroke");

  // 1. The joint move to the approach pose, then a short hold.
  std::size_t kk = 0;
  for (double t = 0.0; t < s[i_app].t; t += dt) {
    while (kk + 1 < i_app && s[kk + 1].t <= t) ++kk;
    const PathSample& a = s[kk];
    const PathSample& b = s[kk + 1];
    const double u = std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0);
    drive_joints(a.q + u * (b.q - a.q), a.qd + u * (b.qd - a.qd));
  }
  for (int i = 0; i < 300; ++i) drive_joints(s[i_app].q, zero);
  q_hold = q;

  // 2.-4. Cartesian impedance: approach, contact and ramp, strokes, retreat.
  const Eigen::Matrix3d rot = s[i_wall].tcp.linear();
  z_ee = rot.col(2);
  ForceAdmittance law(params.force, params.admittance);
  const double abort_force = std::isfinite(params.abort_force) ? params.abort_force : 2.0 * params.force + 20.0;
  PlanCursor cursor{&s, i_app};
  double t_sim = 0.0, next_law = 0.0, next_trace = 0.0, offset = 0.0, over_time = 0.0;
  const double t_contact = params.admittance.ramp_time + params.start_delay;
  double plan_t = s[i_app].t;
  enum class Phase { kApproach, kContact, kStrokes, kRetreat, kDone } phase = Phase::kApproach;
  double phase_t = 0.0, retreat_clock = 0.0, retreat_len = 0.0;
  double abs_err_sum = 0.0, window_sum = 0.0, raw_sum = 0.0, raw_sum2 = 0.0;
  int n_raw = 0, n_contact = 0;
  std::deque<double> window;
  const auto window_n = static_cast<std::size_t>(std::max(1.0, std::round(params.truth_window / dt)));
  int n_stroke = 0;
  const double limit = s.back().t + t_contact + 120.0;
  while (phase != Phase::kDone && t_sim < limit) {
    Eigen::Vector3d p, v;
    const PathSample* at = nullptr;
    cursor.at(plan_t, p, v, &at);
    const double est = -wrench.head<3>().dot(z_ee);  // the force pushed along z_ee
    const bool law_on = phase == Phase::kContact || phase == Phase::kStrokes;
    if (law_on && t_sim + 1e-9 >= next_law) {
      offset = law.update(est, params.command_period);
      next_law = t_sim + params.command_period;
    }
    double ref_offset = offset;
    if (phase == Phase::kRetreat) {
      // Leaving the wall: the offset back to none over the retreat (on the plan's retreat
      // segment), or, after an abort, straight back off the wall from where it was.
      const double u = std::min(1.0, retreat_clock / retreat_len);
      ref_offset = offset * (1.0 - u) - (result.aborted.empty() ? 0.0 : params.path.approach * u);
    }
    Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
    target.linear() = rot;
    target.translation() = p + ref_offset * z_ee;
    drive_cartesian(target, v);
    t_sim += dt;
    phase_t += dt;
    result.max_offset = std::max(result.max_offset, std::abs(offset));

    const bool stroke = phase == Phase::kStrokes && at->tool_on;
    const Eigen::Isometry3d base_now = hw.base_pose();
    const double raw_truth = -hw.contact_force_on(tool_links).dot(base_now.linear() * z_ee);
    // The true force averaged over truth_window: MuJoCo's per-step contact force flickers
    // (see SandRunParams::truth_window); the average is the impulse the wall received.
    window_sum += raw_truth;
    window.push_back(raw_truth);
    if (window.size() > window_n) {
      window_sum -= window.front();
      window.pop_front();
    }
    const double truth = window_sum / static_cast<double>(window.size());
    if (stroke) {
      ++n_raw;
      raw_sum += raw_truth;
      raw_sum2 += raw_truth * raw_truth;
      if (raw_truth > 0.5) ++n_contact;
      const double e = std::abs(truth - params.force);
      result.max_truth_error = std::max(result.max_truth_error, e);
      abs_err_sum += e;
      ++n_stroke;
      const Eigen::Vector3d d = ee.translation() - p;
      result.max_lateral_error = std::max(result.max_lateral_error, (d - d.dot(z_ee) * z_ee).norm());
    }
    if (t_sim + 1e-9 >= next_trace) {
      result.trace.push_back(ForceSample{t_sim, est, truth, stroke});
      next_trace = t_sim + params.trace_period;
    }
    if (law_on) {
      over_time = est > abort_force ? over_time + dt : 0.0;
      if (over_time > 0.05 && result.aborted.empty()) {
        char b[160];
        std::snprintf(b, sizeof b, "force %.1f N above %.1f N for 50 ms at %.2f s: left the wall", est, abort_force, t_sim);
        result.aborted = b;
        phase = Phase::kRetreat;
        retreat_clock = 0.0;
        retreat_len = params.path.approach / params.path.approach_speed;
        continue;
      }
    }
    switch (phase) {
      case Phase::kApproach:
        plan_t += dt;
        if (plan_t >= s[i_wall].t) {
          plan_t = s[i_wall].t;
          phase = Phase::kContact;
          phase_t = 0.0;
        }
        break;
      case Phase::kContact:
        if (phase_t >= t_contact) phase = Phase::kStrokes;
        break;
      case Phase::kStrokes:
        plan_t += dt;
        if (plan_t >= s[i_last].t) {
          plan_t = s[i_last].t;
          phase = Phase::kRetreat;
          retreat_clock = 0.0;
          retreat_len = std::max(s.back().t - plan_t, 0.1);
        }
        break;
      case Phase::kRetreat:
        retreat_clock += dt;
        if (result.aborted.empty()) plan_t += dt;
        if (retreat_clock >= retreat_len + 0.3) phase = Phase::kDone;
        break;
      case Phase::kDone:
        break;
    }
  }
  if (phase != Phase::kDone) throw FinishError("sand run: did not finish within the time limit");
  result.sim_time = hw.time();
  result.estimated = force_stats(result.trace, params.force, params.tolerance);
  std::vector<ForceSample> truth_trace = result.trace;
  for (ForceSample& f : truth_trace) f.estimated = f.truth;
  result.truth = force_stats(truth_trace, params.force, params.tolerance);
  result.truth_within_10 = force_stats(truth_trace, params.force, 10.0).within_fraction;
  result.mean_abs_truth_error = n_stroke > 0 ? abs_err_sum / n_stroke : 0.0;
  if (n_raw > 0) {
    result.raw_truth_mean = raw_sum / n_raw;
    result.raw_truth_std = std::sqrt(std::max(0.0, raw_sum2 / n_raw - result.raw_truth_mean * result.raw_truth_mean));
    result.contact_step_fraction = static_cast<double>(n_contact) / n_raw;
  }
  if (!params.output_stem.empty()) {
    std::ofstream(params.output_stem + ".json") << sand_report_json(result, params) << "\n";
    write_force_png(result.trace, params.force, params.tolerance, params.output_stem + ".png");
    std::ofstream csv(params.output_stem + ".csv");
    csv << "t_s,estimated_n,truth_n,stroke\n";
    for (const ForceSample& f : result.trace) csv << f.t << "," << f.estimated << "," << f.truth << "," << f.stroke << "\n";
  }
  result.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_clock).count();
  return result;
}

std::string sand_report_json(const SandRunResult& r, const SandRunParams& p) {
  auto stats = [](const ForceStats& s) {
    return nlohmann::json{{"mean_n", s.mean},           {"min_n", s.min},
                          {"max_n", s.max},             {"std_n", s.std_dev},
                          {"within_percent", 100.0 * s.within_fraction},
                          {"time_outside_s", s.time_outside}};
  };
  nlohmann::json j{{"rect", r.rect.str()},
                   {"strokes", r.plan.strokes.size()},
                   {"setpoint_n", p.force},
                   {"tolerance_n", p.tolerance},
                   {"stroke_time_s", r.truth.duration},
                   {"speed_m_s", p.path.speed},
                   {"estimated", stats(r.estimated)},
                   {"truth", stats(r.truth)},
                   {"truth_max_error_n", r.max_truth_error},
                   {"truth_mean_abs_error_n", r.mean_abs_truth_error},
                   {"estimate_vs_truth_rms_n", r.estimated.estimate_error_rms},
                   {"max_admittance_offset_mm", r.max_offset * 1e3},
                   {"max_lateral_error_mm", r.max_lateral_error * 1e3},
                   {"truth_window_ms", p.truth_window * 1e3},
                   {"raw_truth_mean_n", r.raw_truth_mean},
                   {"raw_truth_std_n", r.raw_truth_std},
                   {"contact_step_percent", 100.0 * r.contact_step_fraction},
                   {"truth_within_10n_percent", 100.0 * r.truth_within_10},
                   {"aborted", r.aborted}};
  return j.dump(2);
}

}  // namespace concert::surface_finish
