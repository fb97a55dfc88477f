#include "safety/safety_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include "concert/common/enum_map.hpp"
#include "concert/model/limit_checks.hpp"

namespace concert::safety {
namespace {

std::string fixed(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, value);
  return buf;
}

std::string seconds(std::chrono::nanoseconds d) {
  return fixed(std::chrono::duration<double>(d).count(), 2) + " s";
}

using namespace std::string_view_literals;

// What causes and messages call each e-stop input.
constexpr EnumMap kEStopNames{std::array{
    std::pair{EStopSource::kButtonFrontLeft, "button front left"sv},
    std::pair{EStopSource::kButtonFrontRight, "button front right"sv},
    std::pair{EStopSource::kButtonRearLeft, "button rear left"sv},
    std::pair{EStopSource::kButtonRearRight, "button rear right"sv},
    std::pair{EStopSource::kWireless, "wireless"sv},
    std::pair{EStopSource::kSoftware, "software"sv},
}};

}  // namespace

std::string_view to_string(EStopSource source) {
  return kEStopNames.to(source).value_or("unknown");
}

SafetyMonitor::SafetyMonitor(Params params, TimePoint start)
    : params_(std::move(params)), start_(start) {
  if (params_.liveliness_timeout <= std::chrono::milliseconds::zero()) {
    throw std::invalid_argument("liveliness_timeout must be positive");
  }
}

void SafetyMonitor::stop(const std::string& key, const std::string& text) {
  const bool known = std::find(cause_keys_.begin(), cause_keys_.end(), key) != cause_keys_.end();
  if (known && status_.mode == Mode::kStopped) return;
  if (!known) {
    cause_keys_.push_back(key);
    status_.causes.push_back(text);
  }
  status_.mode = Mode::kStopped;
  status_.reset_required = true;
  ++revision_;
  ++latched_revision_;
}

void SafetyMonitor::set_estop(EStopSource source, bool engaged, const std::string& reason) {
  const auto i = static_cast<std::size_t>(source);
  if (i >= kEStopSourceCount)
    throw std::invalid_argument("unknown e-stop source " + std::to_string(i));
  if (engaged_[i] != engaged) {
    engaged_[i] = engaged;
    status_.engaged = engaged_sources();
    ++revision_;
    ++latched_revision_;
  }
  if (engaged) {
    std::string text = "estop: " + std::string(to_string(source)) + " engaged";
    if (!reason.empty()) text += " (" + reason + ")";
    stop("estop:" + std::string(to_string(source)), text);
  }
}

bool SafetyMonitor::is_watched(const std::string& service) const {
  return service == params_.robot_service ||
         std::find(params_.task_services.begin(), params_.task_services.end(), service) !=
             params_.task_services.end();
}

void SafetyMonitor::on_heartbeat(const std::string& service, const std::string& host,
                                 bool clean_stop, TimePoint now, const std::string& incarnation) {
  if (!is_watched(service)) return;
  if (restored_unheard_) {
    // The first watched service heard after a restore: the wire is heard from now on, and a
    // restored instance silent for the bound from here is silent. (Not any status: our own
    // reaches us before the other processes' writers have matched.)
    restored_unheard_ = false;
    for (auto& [who, instance] : instances_) instance.last_seen = std::max(instance.last_seen, now);
  }
  const std::string who = service + "@" + host;
  const bool robot = service == params_.robot_service;
  if (clean_stop) {
    if (instances_.erase(who) > 0) ++latched_revision_;
    if (robot) stop("stopped:" + who, "liveliness: " + who + " stopped (nothing holds the drives)");
    return;
  }
  if (robot) robot_heard_ = true;
  auto [it, inserted] = instances_.try_emplace(who, Instance{service, now, false, incarnation});
  if (inserted) {
    ++latched_revision_;
    return;
  }
  Instance& instance = it->second;
  if (!incarnation.empty() && incarnation != instance.incarnation) {
    // Another process: the one watched died without a goodbye. Already stopped for its silence,
    // that cause names it; else this one does.
    if (!instance.incarnation.empty() && !instance.silent) {
      stop("restarted:" + who, "liveliness: " + who +
                                   " restarted (its process died without stopping; a new one "
                                   "took its place)");
    }
    instance.incarnation = incarnation;
    ++latched_revision_;
  }
  instance.last_seen = std::max(instance.last_seen, now);
  instance.silent = false;
}

void SafetyMonitor::check_liveliness(TimePoint now) {
  if (last_check_ && params_.stall_checks > 0 &&
      now - *last_check_ > params_.stall_checks * params_.check_period) {
    // The monitor itself did not run (a starved process on a loaded machine: its listeners
    // had not taken in the heartbeats waiting for it either). Time it did not watch is not
    // silence it heard: every instance's silence counts on from here, so a service dead
    // meanwhile is caught that much later, and a stall of the safety service alone is no stop.
    const auto asleep = now - *last_check_;
    for (auto& [who, instance] : instances_)
      instance.last_seen = std::min(now, instance.last_seen + asleep);
    ++own_stalls_;
  }
  last_check_ = now;
  if (restored_unheard_) {
    // Nothing watched heard since the restore: silence means nothing yet, unless it lasts
    // (every watched service died while the safety service was down).
    if (now - restored_at_ < 5 * params_.liveliness_timeout) return;
    restored_unheard_ = false;
    for (auto& [who, instance] : instances_) instance.last_seen = now - params_.liveliness_timeout;
  }
  for (auto& [who, instance] : instances_) {
    const auto silent_for = now - instance.last_seen;
    if (instance.silent || silent_for <= params_.liveliness_timeout) continue;
    instance.silent = true;
    stop("silent:" + who, "liveliness: " + who + " silent for " + seconds(silent_for) + " (bound " +
                              seconds(params_.liveliness_timeout) + ")");
  }
  if (params_.require_robot && !robot_heard_ && !robot_start_cause_ &&
      now - start_ > params_.liveliness_timeout) {
    robot_start_cause_ = true;
    stop("silent:" + params_.robot_service,
         "liveliness: " + params_.robot_service + " not heard within " +
             seconds(params_.liveliness_timeout) + " of the start");
  }
}

void SafetyMonitor::set_model(uint32_t version, model::LimitsTable limits) {
  model_version_ = version;
  limits_ = std::move(limits);
  joint_index_.clear();
  for (std::size_t i = 0; i < limits_.size(); ++i) joint_index_[limits_.rows()[i].name] = i;
  thermal_.assign(limits_.size(), model::ThermalLoad{});
  last_sample_.reset();
  last_stamp_ns_.reset();
}

void SafetyMonitor::check_joint(std::size_t row, std::size_t i, const JointSample& sample, double dt) {
  const model::JointLimits& limits = limits_.rows()[row];
  // Stops with "limits: joint NAME WHAT (model vN)", once per joint and `kind` of limit.
  const auto violation = [&](const std::string& kind, const std::string& what) {
    const std::string version = " (model v" + std::to_string(model_version_) + ")";
    stop("limits:" + limits.name + ":" + kind,
         "limits: joint " + limits.name + " " + what + version);
  };
  const double q = sample.position[i];
  if (model::position_violated(limits, q, params_.position_tolerance)) {
    violation("position", "position " + fixed(q, 3) + " beyond [" + fixed(limits.lower, 3) + ", " +
                              fixed(limits.upper, 3) + "]");
  }
  if (i < sample.velocity.size()) {
    const double qd = sample.velocity[i];
    if (model::velocity_violated(limits, qd, params_.velocity_margin)) {
      violation("velocity", "velocity " + fixed(qd, 3) + " beyond +-" +
                                fixed(model::velocity_bound(limits, params_.velocity_margin), 3));
    }
  }
  if (i < sample.effort.size()) {
    const double tau = sample.effort[i];
    if (model::torque_violated(limits, tau, params_.effort_margin)) {
      violation("effort", "effort " + fixed(tau, 2) + " beyond the peak torque +-" +
                              fixed(model::instant_torque_bound(limits, params_.effort_margin), 2));
      return;
    }
    const double rms = thermal_[row].add(tau, dt);
    const double continuous = model::sustained_torque_bound(limits, params_.effort_margin);
    if (rms > continuous) {
      violation("sustained_effort",
                "RMS effort " + fixed(rms, 2) + " over the " + fixed(model::kThermalWindow, 1) +
                    " s thermal window beyond the continuous torque " + fixed(continuous, 2));
    }
  }
}

double SafetyMonitor::sample_period(int64_t stamp_ns, TimePoint now) {
  double dt = 0.0;
  if (stamp_ns > 0) {
    // A stamp that goes back (a restarted robot's clock) or repeats weighs nothing: the
    // clock starts again from it.
    if (last_stamp_ns_ && stamp_ns > *last_stamp_ns_) dt = 1e-9 * static_cast<double>(stamp_ns - *last_stamp_ns_);
    last_stamp_ns_ = stamp_ns;
  } else if (last_sample_) {
    dt = std::chrono::duration<double>(now - *last_sample_).count();
  }
  if (!last_sample_ || now > *last_sample_) last_sample_ = now;
  return dt;
}

SampleOutcome SafetyMonitor::on_joint_state(const JointSample& sample, TimePoint now) {
  if (model_version_ == 0) return SampleOutcome::kNoModel;
  if (sample.model_version != model_version_) return SampleOutcome::kOtherModelVersion;
  const std::size_t n = sample.name.size();
  if (sample.position.size() != n || (!sample.velocity.empty() && sample.velocity.size() != n) ||
      (!sample.effort.empty() && sample.effort.size() != n)) {
    stop("limits:malformed", "limits: malformed joint state: " + std::to_string(n) + " names, " +
                                 std::to_string(sample.position.size()) + " positions, " +
                                 std::to_string(sample.velocity.size()) + " velocities, " +
                                 std::to_string(sample.effort.size()) + " efforts");
    return SampleOutcome::kChecked;
  }
  const double dt = sample_period(sample.stamp_ns, now);
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = joint_index_.find(sample.name[i]);
    if (it != joint_index_.end()) check_joint(it->second, i, sample, dt);
  }
  return SampleOutcome::kChecked;
}

ResetOutcome SafetyMonitor::reset(const std::string& source, TimePoint now) {
  const auto engaged = engaged_inputs();
  if (!engaged.empty()) {
    std::string list;
    for (const auto& e : engaged) list += (list.empty() ? "" : ", ") + e;
    return {false, "reset by " + source + " refused: e-stop input(s) still engaged: " + list};
  }
  check_liveliness(now);
  for (const auto& [who, instance] : instances_) {
    if (instance.silent && instance.service == params_.robot_service) {
      return {false, "reset by " + source + " refused: the robot service " + who + " is silent"};
    }
  }
  if (params_.require_robot && !robot_heard_) {
    return {false, "reset by " + source + " refused: the robot service has not been heard"};
  }
  if (status_.mode == Mode::kRunning)
    return {true, "reset by " + source + ": not stopped, nothing to reset"};
  std::string forgotten;
  for (auto it = instances_.begin(); it != instances_.end();) {
    if (it->second.silent) {
      forgotten += (forgotten.empty() ? "" : ", ") + it->first;
      it = instances_.erase(it);
    } else {
      ++it;
    }
  }
  const std::size_t cleared = status_.causes.size();
  status_ = SafetyStatus{};
  cause_keys_.clear();
  robot_start_cause_ = robot_heard_;
  ++revision_;
  ++latched_revision_;
  std::string message =
      "reset by " + source + " accepted: " + std::to_string(cleared) + " cause(s) cleared";
  if (!forgotten.empty()) message += "; no longer watching silent " + forgotten;
  return {true, message};
}

LatchedState SafetyMonitor::latched() const {
  LatchedState s;
  s.mode = status_.mode;
  s.causes = status_.causes;
  s.cause_keys = cause_keys_;
  for (std::size_t i = 0; i < kEStopSourceCount; ++i) {
    if (engaged_[i]) s.engaged.push_back(static_cast<EStopSource>(i));
  }
  for (const auto& [who, instance] : instances_) s.watched[who] = instance.incarnation;
  return s;
}

void SafetyMonitor::restore(const LatchedState& state, TimePoint now) {
  if (state.causes.size() != state.cause_keys.size())
    throw std::invalid_argument("a latched state needs one key per cause");
  status_.mode = state.mode;
  status_.reset_required = state.mode == Mode::kStopped;
  status_.causes = state.causes;
  cause_keys_ = state.cause_keys;
  engaged_.fill(false);
  for (const auto e : state.engaged) engaged_.at(static_cast<std::size_t>(e)) = true;
  status_.engaged = engaged_sources();
  instances_.clear();
  for (const auto& [who, incarnation] : state.watched) {
    const std::string service = who.substr(0, who.find('@'));
    if (!is_watched(service)) continue;
    instances_[who] = Instance{service, now, false, incarnation};
    if (service == params_.robot_service) robot_heard_ = true;
  }
  robot_start_cause_ = robot_heard_;
  restored_unheard_ = !instances_.empty();
  restored_at_ = now;
  ++revision_;
  ++latched_revision_;
}

std::vector<EStopSource> SafetyMonitor::engaged_sources() const {
  std::vector<EStopSource> out;
  for (std::size_t i = 0; i < kEStopSourceCount; ++i) {
    if (engaged_[i]) out.push_back(static_cast<EStopSource>(i));
  }
  return out;
}

std::vector<std::string> SafetyMonitor::engaged_inputs() const {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < kEStopSourceCount; ++i) {
    if (engaged_[i]) out.emplace_back(to_string(static_cast<EStopSource>(i)));
  }
  return out;
}

std::vector<std::pair<std::string, bool>> SafetyMonitor::watched() const {
  std::vector<std::pair<std::string, bool>> out;
  for (const auto& [who, instance] : instances_) out.emplace_back(who, instance.silent);
  return out;
}

}  // namespace concert::safety
