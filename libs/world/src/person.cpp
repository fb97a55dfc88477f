#include "concert/world/person.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace concert::world {

namespace {

[[noreturn]] void bad(const char* field, const std::string& expected, double got) {
  std::ostringstream s;
  s << "person: " << field << ": expected " << expected << ", got " << got;
  throw std::invalid_argument(s.str());
}

}  // namespace

void check(const PersonParams& p) {
  const auto positive = [](const char* field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) bad(field, "a positive number", v);
  };
  positive("stiffness", p.stiffness);
  if (!(std::isfinite(p.damping) && p.damping >= 0.0)) bad("damping", "a number >= 0", p.damping);
  positive("speed", p.speed);
  if (!(std::isfinite(p.ramp) && p.ramp >= 0.0)) bad("ramp", "a number >= 0", p.ramp);
  positive("let_go_stretch", p.let_go_stretch);
  if (!(std::isfinite(p.wait_stretch) && p.wait_stretch > 0.0 && p.wait_stretch < p.let_go_stretch)) {
    std::ostringstream e;
    e << "a number in (0, let_go_stretch = " << p.let_go_stretch << ")";
    bad("wait_stretch", e.str(), p.wait_stretch);
  }
  positive("arrive_radius", p.arrive_radius);
  if (!(std::isfinite(p.arrive_time) && p.arrive_time >= 0.0)) bad("arrive_time", "a number >= 0", p.arrive_time);
}

const char* to_string(PersonPhase phase) {
  switch (phase) {
    case PersonPhase::kAbsent: return "absent";
    case PersonPhase::kGuiding: return "guiding";
    case PersonPhase::kHolding: return "holding";
    case PersonPhase::kWalking: return "walking";
    case PersonPhase::kWaiting: return "waiting";
    case PersonPhase::kArrived: return "arrived";
    case PersonPhase::kLetGo: return "let go";
  }
  return "?";
}

SimPerson::SimPerson(PersonParams params) : params_(params) { check(params_); }

bool SimPerson::gripping() const { return phase_ != PersonPhase::kAbsent && phase_ != PersonPhase::kLetGo; }

void SimPerson::grip(double t, const Eigen::Vector3d& tcp, const Eigen::Vector3d& guide, double guide_time) {
  if (!tcp.allFinite() || !guide.allFinite() || !std::isfinite(guide_time))
    throw std::invalid_argument("person: grip: the link's position and the guide must be finite");
  phase_ = guide_time > 0.0 ? PersonPhase::kGuiding : PersonPhase::kHolding;
  reason_.clear();
  last_t_ = t;
  hand_ = tcp;
  hand_velocity_.setZero();
  pull_.setZero();
  peak_pull_ = 0.0;
  guide_from_ = tcp;
  guide_ = guide_time > 0.0 ? guide : Eigen::Vector3d::Zero();
  guide_start_ = t;
  guide_time_ = guide_time;
  route_.clear();
  along_.clear();
  walked_ = 0.0;
}

void SimPerson::walk(double t, std::vector<Eigen::Vector2d> route) {
  if (!gripping()) throw std::logic_error("person: walk: the person holds nothing (grip first)");
  if (route.empty()) throw std::invalid_argument("person: walk: the route has no point");
  for (const Eigen::Vector2d& p : route) {
    if (!p.allFinite()) throw std::invalid_argument("person: walk: a route point is not finite");
  }
  route_.assign(1, hand_.head<2>());
  route_.insert(route_.end(), route.begin(), route.end());
  along_.assign(1, 0.0);
  for (std::size_t i = 1; i < route_.size(); ++i) along_.push_back(along_.back() + (route_[i] - route_[i - 1]).norm());
  walked_ = 0.0;
  moving_for_ = 0.0;
  arrived_for_ = 0.0;
  last_t_ = t;
  hand_velocity_.setZero();
  phase_ = PersonPhase::kWalking;
}

void SimPerson::let_go(std::string reason) {
  if (!gripping()) return;
  phase_ = PersonPhase::kLetGo;
  reason_ = std::move(reason);
  hand_velocity_.setZero();
  pull_.setZero();
}

double SimPerson::route_length() const { return along_.empty() ? 0.0 : along_.back(); }

Eigen::Vector2d SimPerson::route_at(double s) const {
  for (std::size_t i = 1; i < route_.size(); ++i) {
    if (s <= along_[i] || i + 1 == route_.size()) {
      const double seg = along_[i] - along_[i - 1];
      const double a = seg > 0.0 ? std::clamp((s - along_[i - 1]) / seg, 0.0, 1.0) : 1.0;
      return route_[i - 1] + a * (route_[i] - route_[i - 1]);
    }
  }
  return route_.back();
}

void SimPerson::step_guide(double t) {
  const double a = std::min(1.0, (t - guide_start_) / guide_time_);
  hand_ = guide_from_ + a * guide_;
  if (a < 1.0) {
    hand_velocity_ = guide_ / guide_time_;
  } else {
    hand_velocity_.setZero();
    phase_ = PersonPhase::kHolding;
  }
}

void SimPerson::step_walk(double dt, const Eigen::Vector3d& tcp) {
  const double stretch = (hand_.head<2>() - tcp.head<2>()).norm();
  if (stretch > params_.let_go_stretch) {
    std::ostringstream why;
    why.precision(2);
    why << std::fixed << "the robot fell " << stretch << " m behind the hand (more than " << params_.let_go_stretch
        << " m) after " << walked_ << " of " << route_length() << " m";
    let_go(why.str());
    return;
  }
  const bool end = walked_ >= route_length();
  if (!end && stretch > params_.wait_stretch) {
    // The robot lags: the person stands and waits for it, and gets going again gently.
    phase_ = PersonPhase::kWaiting;
    moving_for_ = 0.0;
    hand_velocity_.setZero();
    return;
  }
  if (!end) {
    phase_ = PersonPhase::kWalking;
    moving_for_ += dt;
    const double speed = params_.ramp > 0.0 ? params_.speed * std::min(1.0, moving_for_ / params_.ramp) : params_.speed;
    walked_ = std::min(route_length(), walked_ + speed * dt);
    const Eigen::Vector2d next = route_at(walked_);
    hand_velocity_.head<2>() = (next - hand_.head<2>()) / dt;
    hand_velocity_.z() = 0.0;
    hand_.head<2>() = next;
    return;
  }
  hand_velocity_.setZero();
  if (phase_ == PersonPhase::kArrived) return;
  arrived_for_ = (route_.back() - tcp.head<2>()).norm() < params_.arrive_radius ? arrived_for_ + dt : 0.0;
  if (arrived_for_ >= params_.arrive_time) phase_ = PersonPhase::kArrived;
}

Eigen::Vector3d SimPerson::force(double t, const Eigen::Vector3d& tcp, const Eigen::Vector3d& tcp_velocity) {
  if (!gripping()) return Eigen::Vector3d::Zero();
  const double dt = t - last_t_;
  last_t_ = t;
  if (dt > 0.0) {
    if (phase_ == PersonPhase::kGuiding) {
      step_guide(t);
    } else if (phase_ == PersonPhase::kWalking || phase_ == PersonPhase::kWaiting || phase_ == PersonPhase::kArrived) {
      step_walk(dt, tcp);
      if (!gripping()) return Eigen::Vector3d::Zero();
    }
  }
  pull_ = params_.stiffness * (hand_ - tcp) + params_.damping * (hand_velocity_ - tcp_velocity);
  peak_pull_ = std::max(peak_pull_, pull_.norm());
  return pull_;
}

}  // namespace concert::world
