#include "surface_finish/sand_sequence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "concert/model/same_arm.hpp"

namespace concert::surface_finish {

const char* to_string(SandPhase phase) {
  switch (phase) {
    case SandPhase::kMove:
      return "move";
    case SandPhase::kApproach:
      return "approach";
    case SandPhase::kContact:
      return "contact";
    case SandPhase::kStrokes:
      return "strokes";
    case SandPhase::kUnload:
      return "unload";
    case SandPhase::kRetreat:
      return "retreat";
    case SandPhase::kLeaving:
      return "leaving";
    case SandPhase::kHeld:
      return "held";
    case SandPhase::kDone:
      return "done";
    case SandPhase::kAborted:
      return "aborted";
  }
  return "?";
}

SandSequence::SandSequence(SerpentinePlan plan, SandParams params)
    : plan_(std::move(plan)), params_(params) {
  const SandParams& p = params_;
  if (!(p.force > 0.0) || !std::isfinite(p.force)) {
    char b[120];
    std::snprintf(b, sizeof b, "the force setpoint must be positive (got %g N)", p.force);
    throw FinishError(b);
  }
  if (!(p.tolerance > 0.0) || !(p.ramp_time >= 0.0) || !(p.start_delay >= 0.0) ||
      !(p.unload_time >= 0.0) || !(p.admittance_gain > 0.0) || !(p.stiffness > 0.0) ||
      !(p.rot_stiffness > 0.0) || !(p.damping_ratio >= 0.0) || !(p.abort_time >= 0.0) ||
      !(p.lost_contact_fraction >= 0.0) || !(p.lost_contact_time > 0.0) || !(p.leave_time > 0.0) || !(p.contact_gap >= 0.0)) {
    throw FinishError(
        "sand parameters: tolerance, admittance gain, stiffnesses, lost-contact and leave times > "
        "0; ramp, delay, unload, abort time, damping ratio, lost-contact fraction and contact gap >= 0");
  }
  if (std::isfinite(p.abort_force) && !(p.abort_force > p.force)) {
    throw FinishError("sand parameters: the abort force must exceed the setpoint");
  }
  const auto& s = plan_.samples;
  const double off = plan_.tool.standoff + plan_.params.approach;
  bool app = false, wall = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!app && std::abs(s[i].wall.z() - off) < 1e-6) {
      i_app_ = i;
      app = true;
    }
    if (!wall && s[i].stroke == 0 && i > 0) {
      i_wall_ = i - 1;
      wall = true;
    }
    if (s[i].stroke >= 0) i_last_ = i;
  }
  if (!app || !wall || i_wall_ <= i_app_ || i_last_ <= i_wall_ || i_app_ == 0) {
    throw FinishError("sand run: the plan has no joint move, approach or stroke");
  }
  z_ee_ = s[i_wall_].tcp.linear().col(2);
  if (!(p.contact_gap < plan_.params.approach)) {
    char b[160];
    std::snprintf(b, sizeof b, "sand parameters: the contact gap %.3f m must be less than the plan's approach %.3f m",
                  p.contact_gap, plan_.params.approach);
    throw FinishError(b);
  }
}

void SandSequence::start(double t) {
  if (phase_ != SandPhase::kMove) return;
  phase_ = SandPhase::kApproach;
  phase_start_ = t;
  now_ = t;
  move_progress_ = 1.0;
  plan_t_ = plan_.samples[i_app_].t;
  (void)update(t);  // the first target: a stop before the next tick leaves from there
}

double SandSequence::abort_force() const {
  return std::isfinite(params_.abort_force) ? params_.abort_force : 2.0 * params_.force + 20.0;
}

const PathSample& SandSequence::at(double plan_t, Eigen::Vector3d& p, Eigen::Vector3d& v) const {
  const auto& s = plan_.samples;
  // The sample at or before plan_t (binary search on time).
  auto it = std::upper_bound(s.begin(), s.end(), plan_t,
                             [](double t, const PathSample& a) { return t < a.t; });
  std::size_t k = it == s.begin() ? 0 : static_cast<std::size_t>(it - s.begin()) - 1;
  k = std::min(k, s.size() - 1);
  const PathSample& a = s[k];
  const PathSample& b = s[std::min(k + 1, s.size() - 1)];
  const double dt = b.t - a.t;
  const double u = dt > 0.0 ? std::clamp((plan_t - a.t) / dt, 0.0, 1.0) : 1.0;
  p = a.tcp.translation() + u * (b.tcp.translation() - a.tcp.translation());
  v = dt > 0.0 && plan_t >= a.t && plan_t < b.t
          ? Eigen::Vector3d((b.tcp.translation() - a.tcp.translation()) / dt)
          : Eigen::Vector3d::Zero();
  return b;
}

SandCommand SandSequence::update(double t) {
  if (phase_ == SandPhase::kMove || phase_ == SandPhase::kHeld || finished()) return last_;
  now_ = std::max(now_, t);
  const auto& s = plan_.samples;
  const SandParams& p = params_;
  // Phase changes at the time they were due (a late tick does not stretch a phase).
  for (bool again = true; again;) {
    again = false;
    const double in = now_ - phase_start_;
    switch (phase_) {
      case SandPhase::kApproach:
        plan_t_ = s[i_app_].t + in;
        if (plan_t_ >= s[i_wall_].t) {
          phase_ = SandPhase::kContact;
          phase_start_ += s[i_wall_].t - s[i_app_].t;
          again = true;
        }
        break;
      case SandPhase::kContact:
        plan_t_ = s[i_wall_].t;
        if (in >= p.ramp_time + p.start_delay) {
          phase_ = SandPhase::kStrokes;
          phase_start_ += p.ramp_time + p.start_delay;
          again = true;
        }
        break;
      case SandPhase::kStrokes:
        plan_t_ = s[i_wall_].t + in;
        if (plan_t_ >= s[i_last_].t) {
          phase_ = SandPhase::kUnload;
          phase_start_ += s[i_last_].t - s[i_wall_].t;
          again = true;
        }
        break;
      case SandPhase::kUnload:
        plan_t_ = s[i_last_].t;
        if (in >= p.unload_time) {
          phase_ = SandPhase::kRetreat;
          phase_start_ += p.unload_time;
          again = true;
        }
        break;
      case SandPhase::kRetreat:
        plan_t_ = std::min(s[i_last_].t + in, s.back().t);
        if (s[i_last_].t + in >= s.back().t) phase_ = SandPhase::kDone;
        break;
      case SandPhase::kLeaving:
        if (in >= p.leave_time) phase_ = SandPhase::kAborted;
        break;
      default:
        break;
    }
  }
  SandCommand c;
  const double kt = p.stiffness, kr = p.rot_stiffness;
  const double dtr = 2.0 * p.damping_ratio * std::sqrt(kt * 10.0),
               drot = 2.0 * p.damping_ratio * std::sqrt(kr * 0.5);
  c.stiffness = {kt, kt, kt, kr, kr, kr};
  c.damping = {dtr, dtr, dtr, drot, drot, drot};
  c.target.linear() = s[i_wall_].tcp.linear();
  if (phase_ == SandPhase::kLeaving || phase_ == SandPhase::kAborted) {
    const double u = std::min(1.0, (now_ - phase_start_) / p.leave_time);
    c.target = leave_from_;
    c.target.translation() -= u * plan_.params.approach * z_ee_;
    if (u < 1.0) c.velocity = -plan_.params.approach / p.leave_time * z_ee_;
  } else {
    Eigen::Vector3d pos, vel;
    (void)at(plan_t_, pos, vel);
    // Held contact_gap in front of the plan's path, reached over the approach.
    const double t_app = s[i_app_].t, t_wall = s[i_wall_].t;
    const double share = phase_ == SandPhase::kApproach && t_wall > t_app
                             ? std::clamp((plan_t_ - t_app) / (t_wall - t_app), 0.0, 1.0)
                             : 1.0;
    c.target.translation() = pos - share * p.contact_gap * z_ee_;
    if (phase_ == SandPhase::kApproach && plan_t_ < t_wall) vel -= p.contact_gap / (t_wall - t_app) * z_ee_;
    if (phase_ == SandPhase::kApproach || phase_ == SandPhase::kStrokes ||
        phase_ == SandPhase::kRetreat) {
      c.velocity = vel;
    }
    const double in = now_ - phase_start_;
    c.admittance_gain = p.admittance_gain;
    if (phase_ == SandPhase::kContact) {
      c.admittance = true;
      c.force_setpoint = p.ramp_time > 0.0 ? p.force * std::min(1.0, in / p.ramp_time) : p.force;
    } else if (phase_ == SandPhase::kStrokes) {
      c.admittance = true;
      c.force_setpoint = p.force;
    } else if (phase_ == SandPhase::kUnload) {
      c.admittance = true;
      c.force_setpoint =
          p.unload_time > 0.0 ? p.force * std::max(0.0, 1.0 - in / p.unload_time) : 0.0;
    }
  }
  last_ = c;
  return c;
}

bool SandSequence::stroking(double t) const {
  if (phase_ != SandPhase::kStrokes) return false;
  Eigen::Vector3d pos, vel;
  const double plan_t = plan_.samples[i_wall_].t + (t - phase_start_);
  if (plan_t > plan_.samples[i_last_].t) return false;
  return at(plan_t, pos, vel).tool_on;
}

void SandSequence::add_force(double t, double pushed) {
  if (!std::isfinite(pushed)) return;
  const bool cartesian = phase_ == SandPhase::kApproach || phase_ == SandPhase::kContact ||
                         phase_ == SandPhase::kStrokes || phase_ == SandPhase::kUnload ||
                         phase_ == SandPhase::kRetreat;
  if (!cartesian) return;
  const bool stroke = stroking(t);
  trace_.push_back(ForceSample{t, pushed, std::nan(""), stroke});
  char b[200];
  if (pushed > abort_force()) {
    if (over_since_ < 0.0) over_since_ = t;
    if (t - over_since_ >= params_.abort_time) {
      std::snprintf(b, sizeof b,
                    "the force estimate %.1f N stayed above %.1f N for %.0f ms (setpoint %.1f N)",
                    pushed, abort_force(), (t - over_since_) * 1e3, params_.force);
      leave(b);
      return;
    }
  } else {
    over_since_ = -1.0;
  }
  if (stroke && pushed < params_.lost_contact_fraction * params_.force) {
    if (under_since_ < 0.0) under_since_ = t;
    if (t - under_since_ >= params_.lost_contact_time) {
      std::snprintf(
          b, sizeof b,
          "contact lost: the force estimate stayed below %.1f N for %.1f s (setpoint %.1f N)",
          params_.lost_contact_fraction * params_.force, t - under_since_, params_.force);
      leave(b);
    }
  } else {
    under_since_ = -1.0;
  }
}

void SandSequence::leave(const std::string& reason) {
  reason_ = reason;
  leave_from_ = last_.target;
  if (measured_tcp_) leave_from_.translation() = measured_tcp_->translation();
  if (phase_ == SandPhase::kMove) {
    phase_ = SandPhase::kAborted;
    return;
  }
  phase_ = SandPhase::kLeaving;
  phase_start_ = now_;
}

void SandSequence::stop(const std::string& reason) {
  if (finished()) return;
  reason_ = reason;
  phase_ = SandPhase::kAborted;
}

bool SandSequence::abort(const std::string& reason) {
  if (finished()) return false;
  if (phase_ == SandPhase::kLeaving) return true;  // on its way off the wall already
  if (phase_ == SandPhase::kMove || phase_ == SandPhase::kHeld) {
    // The joint move stops where it is; a held run stays held until the stop is reset.
    if (phase_ == SandPhase::kMove) stop(reason);
    return phase_ == SandPhase::kHeld;
  }
  leave(reason);
  return true;
}

void SandSequence::hold_for_safety(const std::string& reason) {
  if (finished() || phase_ == SandPhase::kHeld) return;
  if (phase_ == SandPhase::kMove) {
    stop(reason);
    return;
  }
  reason_ = reason;
  phase_ = SandPhase::kHeld;
}

void SandSequence::resume_leaving(double t) {
  if (phase_ != SandPhase::kHeld) return;
  now_ = std::max(now_, t);
  leave(reason_ + "; the tool left the wall after the reset");
}

double SandSequence::progress() const {
  const auto& s = plan_.samples;
  const double total = s.back().t;
  if (total <= 0.0) return 0.0;
  if (phase_ == SandPhase::kDone) return 1.0;
  if (phase_ == SandPhase::kMove) return std::clamp(move_progress_, 0.0, 1.0) * s[i_app_].t / total;
  return std::clamp(plan_t_ / total, 0.0, 1.0);
}

ForceStats SandSequence::stats() const {
  return force_stats(trace_, params_.force, params_.tolerance);
}

std::string SandSequence::report_json() const {
  nlohmann::ordered_json j;
  j["task"] = "sand";
  j["state"] = to_string(phase_);
  j["reason"] = reason_;
  j["force_setpoint_n"] = params_.force;
  j["tolerance_n"] = params_.tolerance;
  j["rect"] = {
      {"x0", plan_.rect.x0}, {"x1", plan_.rect.x1}, {"y0", plan_.rect.y0}, {"y1", plan_.rect.y1}};
  j["strokes"] = plan_.strokes.size();
  j["speed_m_s"] = plan_.params.speed;
  j["plan_duration_s"] = plan_.duration();
  j["force_source"] =
      "the robot service's estimate from the joint torques (concert/robot/ee_wrench), along the "
      "TCP's z";
  j["samples"] = trace_.size();
  const bool any =
      std::any_of(trace_.begin(), trace_.end(), [](const ForceSample& f) { return f.stroke; });
  if (any) {
    const ForceStats st = stats();
    j["stroke_time_s"] = st.duration;
    j["mean_n"] = st.mean;
    j["min_n"] = st.min;
    j["max_n"] = st.max;
    j["std_n"] = st.std_dev;
    j["within_tolerance_percent"] = st.within_fraction * 100.0;
    j["time_outside_s"] = st.time_outside;
  }
  return j.dump(1);
}

namespace {

SandStep ended(SandSequence& seq, SandEnd end, const std::string& why) {
  seq.stop(why);
  return {std::nullopt, end, seq.reason()};
}

}  // namespace

SandStep supervise(SandSequence& seq, const SandCycle& c, const SandWatch& watch) {
  if (c.tcp) seq.set_tcp(*c.tcp);
  if (c.safety_stop) {
    const std::string why = "safety stop (" + *c.safety_stop + ")";
    if (seq.phase() == SandPhase::kMove) return ended(seq, SandEnd::kAborted, why);
    seq.hold_for_safety(why);  // the robot holds; nothing to command until the reset
    return {};
  }
  SandStep step;
  if (seq.phase() == SandPhase::kHeld) {
    if (c.forces.empty()) return step;  // the robot's time: from its next estimate
    seq.resume_leaving(c.forces.back().t);
  }
  if (seq.phase() == SandPhase::kMove) {
    if (c.move != MoveReport::kNoAnswer) seq.set_move_progress(c.move_progress);
    if (c.move == MoveReport::kSucceeded) {
      if (c.forces.empty()) return step;  // the robot's time: from its next estimate
      seq.start(c.forces.back().t);
    } else if (c.move == MoveReport::kStopped) {
      return ended(seq, SandEnd::kFailed, "the robot stopped the move to the approach pose: " + c.move_reason);
    } else if (c.move == MoveReport::kNoAnswer && c.since_sent > watch.move_answer_timeout) {
      char b[120];
      std::snprintf(b, sizeof b, "the robot service did not answer the move's trajectory within %.0f s",
                    watch.move_answer_timeout);
      return ended(seq, SandEnd::kFailed, b);
    }
  }
  if (seq.phase() != SandPhase::kMove) {
    if (c.silence > watch.wrench_timeout) {
      char b[120];
      std::snprintf(b, sizeof b, "no force estimate from the robot (concert/robot/ee_wrench) for %.1f s",
                    watch.wrench_timeout);
      return ended(seq, SandEnd::kAborted, b);
    }
    for (const SandCycle::Force& f : c.forces) {
      (void)seq.update(f.t);
      seq.add_force(f.t, -f.force.dot(seq.normal()));  // the force the disc pushes along z_ee
      if (seq.finished()) break;
    }
    if (!c.forces.empty() && !seq.finished()) {
      SandCommand command = seq.update(c.forces.back().t);
      if (!seq.finished()) step.command = command;
    }
  }
  if (seq.phase() == SandPhase::kDone) {
    step.end = SandEnd::kSucceeded;
  } else if (seq.phase() == SandPhase::kAborted) {
    step.end = SandEnd::kAborted;
    step.reason = seq.reason();
  }
  return step;
}

bool leave_for_new_model(SandSequence& seq, const NewModel& m) {
  std::string why = "the robot model changed to version " + std::to_string(m.version);
  const bool same_arm = m.before && m.after && !m.names.empty() &&
                        model::same_frame_pose(*m.before, *m.after, m.tcp_frame, m.names, m.positions);
  if (same_arm && seq.abort(why)) return true;
  if (!m.after) {
    why += " (" + m.error + "): the arm holds where it is";
  } else if (!same_arm) {
    why += "; the new model's arm is another: the arm holds where it is";
  }
  seq.stop(why);
  return false;
}

}  // namespace concert::surface_finish
