#include "drill/drill_motion.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace concert::drill {
namespace {

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
}

}  // namespace

const char* to_string(DrillMotion::Phase phase) {
  switch (phase) {
    case DrillMotion::Phase::kIdle:
      return "idle";
    case DrillMotion::Phase::kAligning:
      return "aligning";
    case DrillMotion::Phase::kDrilling:
      return "drilling";
    case DrillMotion::Phase::kRetracting:
      return "retracting";
    case DrillMotion::Phase::kDone:
      return "done";
    case DrillMotion::Phase::kFailed:
      return "failed";
  }
  return "unknown";
}

DrillMotion::DrillMotion(DrillParams params) : params_(params) {}

double DrillMotion::depth_of(const Eigen::Isometry3d& tip) const {
  return -(hole_.inverse() * tip.translation()).z();
}

double DrillMotion::lateral_error(const Eigen::Isometry3d& tip) const {
  return (hole_.inverse() * tip.translation()).head<2>().norm();
}

void DrillMotion::start_align(const Eigen::Isometry3d& hole, const Eigen::Isometry3d& tip,
                              double now) {
  hole_ = hole;
  phase_ = Phase::kAligning;
  reason_.clear();
  started_ = last_ = now;
  paused_ = 0.0;
  settled_since_ = -1.0;
  ref_ = tip;
}

void DrillMotion::start_drill(double depth, bool servo, const Eigen::Isometry3d& tip, double now) {
  phase_ = Phase::kDrilling;
  reason_.clear();
  started_ = last_ = now;
  paused_ = 0.0;
  target_depth_ = depth;
  servo_ = servo;
  contact_ = false;
  contact_offset_ = 0.0;
  axial_speed_ = 0.0;
  depth_ref_ = depth_of(tip);
  last_depth_ = depth_ref_;
  reached_ = depth_ref_;
}

void DrillMotion::start_retract(const Eigen::Isometry3d& tip, double now) {
  phase_ = Phase::kRetracting;
  reason_.clear();
  started_ = last_ = now;
  paused_ = 0.0;
  depth_ref_ = depth_of(tip);
  // The bit pulls straight back as it is: turning it onto the hole's axis here would wrench a
  // bit that never got aligned (an alignment that failed far from the hole).
  ref_ = tip;
  if (depth_ref_ <= -params_.standoff || lateral_error(tip) > params_.servo_jump)
    phase_ = Phase::kDone;
}

bool DrillMotion::observe(const Eigen::Isometry3d& hole) {
  const bool before_surface = phase_ == Phase::kAligning ||
                              (phase_ == Phase::kDrilling && servo_ && !contact_ && reached_ < 0.0);
  if (!before_surface) return false;
  if ((hole.translation() - hole_.translation()).norm() > params_.servo_jump) return false;
  hole_ = hole;
  return true;
}

void DrillMotion::move_base(const Eigen::Isometry3d& new_T_old) {
  hole_ = new_T_old * hole_;
  ref_ = new_T_old * ref_;
}

void DrillMotion::fail(const std::string& why) {
  phase_ = Phase::kFailed;
  reason_ = why;
}

// The tip's pose on the hole's axis at `depth`: the bit along -z of the hole frame, turned
// about it as little as possible from the tip's current orientation (the wrist does not spin).
Eigen::Isometry3d DrillMotion::axis_pose(double depth, const Eigen::Isometry3d& tip) const {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d bit = -hole_.linear().col(2);
  out.translation() = hole_.translation() + depth * bit;
  const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(tip.linear().col(2), bit);
  out.linear() = turn.toRotationMatrix() * tip.linear();
  return out;
}

CartesianReference DrillMotion::reference(double depth, double feed,
                                          const Eigen::Isometry3d& tip) const {
  CartesianReference r;
  r.pose = axis_pose(depth, tip);
  r.twist.head<3>() = -feed * hole_.linear().col(2);
  r.stiffness << params_.stiffness, params_.stiffness, params_.stiffness, params_.angular_stiffness,
      params_.angular_stiffness, params_.angular_stiffness;
  r.damping << params_.damping, params_.damping, params_.damping, params_.angular_damping,
      params_.angular_damping, params_.angular_damping;
  return r;
}

void DrillMotion::set_thrust_share(double share) { thrust_share_ = std::clamp(std::isfinite(share) ? share : 1.0, 0.0, 1.0); }

CartesianReference DrillMotion::update(const Eigen::Isometry3d& tip, double now) {
  const double dt = std::max(0.0, now - last_);
  last_ = now;
  const double elapsed = now - started_ - paused_;
  const double depth = depth_of(tip);
  switch (phase_) {
    case Phase::kAligning: {
      // The reference moves from where the tip was to the aligned pose at approach_speed
      // (and turns at most approach_turn per second): a jump would be a force step of
      // stiffness x distance.
      const Eigen::Isometry3d goal = axis_pose(-params_.standoff, tip);
      const Eigen::Vector3d step = goal.translation() - ref_.translation();
      const double max_step = params_.approach_speed * dt;
      ref_.translation() +=
          step.norm() > max_step ? Eigen::Vector3d(step.normalized() * max_step) : step;
      const Eigen::Quaterniond from(ref_.linear()), to(goal.linear());
      const double turn = from.angularDistance(to);
      const double max_turn = params_.approach_turn * dt;
      ref_.linear() = (turn > max_turn ? from.slerp(max_turn / turn, to) : to).toRotationMatrix();
      const double off = (tip.translation() - goal.translation()).norm();
      const double angle = angle_between(tip.linear().col(2), -hole_.linear().col(2));
      if (off < params_.align_tolerance && angle < params_.align_angle) {
        if (settled_since_ < 0.0) settled_since_ = now;
        if (now - settled_since_ >= params_.settle_time) phase_ = Phase::kDone;
      } else {
        settled_since_ = -1.0;
      }
      if (phase_ == Phase::kAligning && elapsed > params_.align_timeout) {
        std::ostringstream s;
        s << "not aligned after " << params_.align_timeout << " s: tip " << off * 1000.0
          << " mm off, bit " << angle * 180.0 / M_PI << " deg off the hole's axis";
        fail(s.str());
      }
      CartesianReference r = reference(-params_.standoff, 0.0, tip);
      r.pose = ref_;
      return r;
    }
    case Phase::kDrilling: {
      double d = depth;
      if (dt > 0.0) {
        // Filtered over about 50 ms: the tip's pose comes at the control rate, with noise.
        axial_speed_ += ((d - last_depth_) / dt - axial_speed_) * std::min(1.0, dt / 0.05);
      }
      last_depth_ = d;
      if (!contact_ && depth_ref_ - d >= params_.contact_lead &&
          axial_speed_ < 0.5 * params_.feed_rate) {
        // The bit pushes and hardly advances: it is on the surface. The hole starts here.
        contact_ = true;
        contact_offset_ = d;
        hole_.translation() -= d * hole_.linear().col(2);
        depth_ref_ -= d;
        last_depth_ = 0.0;
        d = 0.0;
      }
      reached_ = std::max(reached_, d);
      // Eq. 3: the reference advances at v_drill, never more than max_lead ahead of the tip;
      // before the bit meets the wall, at most contact_search beyond the depth asked; after,
      // contact_lead beyond it, a lead that still pushes past the wall's threshold (at 2 mm,
      // 16 N of 20: the light drilling's bit, slower, stops 0.2 mm short of its depth).
      const double limit = target_depth_ + (contact_ ? params_.contact_lead : params_.contact_search);
      // The thermal foldback (set_thrust_share): the lead between light_drilling's floor and
      // max_lead; at 0 in the wall, the reference waits at the tip.
      const double floor = std::min(params_.max_lead, params_.contact_lead + kLeadOverContact);
      const double lead = floor + thrust_share_ * (params_.max_lead - floor);
      if (contact_ && thrust_share_ <= 0.0) {
        paused_ += dt;
        depth_ref_ = std::min(depth_ref_, d);
        if (paused_ > params_.drill_timeout) {
          // The drive does not cool with the bit at rest: the posture itself loads it too much.
          std::ostringstream s;
          s << "the feed stood still " << params_.drill_timeout << " s for the arm's drives to cool, in vain: hole "
            << std::max(0.0, reached_) * 1000.0 << " of " << target_depth_ * 1000.0 << " mm deep";
          fail(s.str());
          return reference(depth_ref_, 0.0, tip);
        }
      } else {
        depth_ref_ = std::min({depth_ref_ + params_.feed_rate * dt, d + lead, limit});
      }
      if (contact_ && d >= target_depth_) {
        phase_ = Phase::kDone;
      } else if (!contact_ && d >= limit - params_.contact_lead) {
        std::ostringstream s;
        s << "no wall felt " << (target_depth_ + params_.contact_search) * 1000.0
          << " mm behind the surface the camera measured: the wall is not where it was seen";
        fail(s.str());
      } else if (elapsed > params_.drill_timeout) {
        std::ostringstream s;
        s << "hole " << std::max(0.0, reached_) * 1000.0 << " of " << target_depth_ * 1000.0
          << " mm deep after " << params_.drill_timeout
          << " s: the wall resists more than the arm pushes";
        fail(s.str());
      }
      return reference(depth_ref_, phase_ == Phase::kDrilling ? params_.feed_rate : 0.0, tip);
    }
    case Phase::kRetracting: {
      const double before = depth_ref_;
      depth_ref_ = std::max(depth_ref_ - params_.approach_speed * dt, -params_.standoff);
      ref_.translation() += (before - depth_ref_) * hole_.linear().col(2);
      if (depth <= -params_.standoff + params_.align_tolerance) {
        phase_ = Phase::kDone;
      } else if (elapsed > params_.retract_timeout) {
        std::ostringstream s;
        s << "bit still " << depth * 1000.0 << " mm deep after " << params_.retract_timeout
          << " s of retracting";
        fail(s.str());
      }
      CartesianReference r = reference(depth_ref_, 0.0, tip);
      r.pose = ref_;
      return r;
    }
    case Phase::kIdle:
    case Phase::kDone:
    case Phase::kFailed:
      break;
  }
  CartesianReference hold = reference(depth, 0.0, tip);
  hold.pose = tip;
  return hold;
}

}  // namespace concert::drill
