#include "drill/inputs.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

#include "drill/perception.hpp"

namespace concert::drill {

namespace {

double seconds_between(Inputs::Clock::time_point from, Inputs::Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace

Inputs::Inputs(Params::Buffers buffers, Params::Liveness liveness)
    : buffers_(buffers), liveness_(liveness) {}

void Inputs::on_joints(std::int64_t stamp_ns, JointPositions joints, Clock::time_point now,
                       const std::vector<double>& efforts) {
  std::lock_guard lock(mutex_);
  joints_seen_ = now;
  if (efforts.size() == joints.names.size() && stamp_ns > load_stamp_ns_) {
    const double dt = load_stamp_ns_ > 0 ? 1e-9 * static_cast<double>(stamp_ns - load_stamp_ns_) : 0.0;
    load_stamp_ns_ = stamp_ns;
    for (std::size_t i = 0; i < efforts.size(); ++i) {
      Load& l = loads_[joints.names[i]];
      l.rms.add(std::abs(efforts[i]), dt);
      l.present.add(std::abs(efforts[i]), dt);
    }
  }
  if (!samples_.empty() && stamp_ns - samples_.back().stamp_ns < buffers_.sample_step.count()) return;
  JointSample sample;
  sample.stamp_ns = stamp_ns;
  sample.joints = std::move(joints);
  if (odometry_) sample.odometry = *odometry_;
  samples_.push_back(std::move(sample));
  while (samples_.size() > buffers_.samples) samples_.pop_front();
}

void Inputs::on_odometry(const Eigen::Vector3d& odometry) {
  std::lock_guard lock(mutex_);
  odometry_ = odometry;
}

void Inputs::on_service(const std::string& service, bool stopped, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  if (stopped) {
    services_seen_.erase(service);
  } else {
    services_seen_[service] = now;
  }
}

void Inputs::on_safety(SafetyWord safety) {
  std::lock_guard lock(mutex_);
  safety_ = std::move(safety);
}

void Inputs::on_plan(const PlanReply& reply) {
  std::lock_guard lock(mutex_);
  merge_reply(plans_[reply.request_id], reply);
}

void Inputs::on_trajectory(std::uint32_t request, MotionReply reply) {
  std::lock_guard lock(mutex_);
  trajectories_[request] = std::move(reply);
}

void Inputs::on_nav(std::uint32_t request, MotionReply reply) {
  std::lock_guard lock(mutex_);
  navs_[request] = std::move(reply);
}

void Inputs::set_rig(std::shared_ptr<const DrillRig> rig) {
  std::lock_guard lock(mutex_);
  rig_ = std::move(rig);
  frames_.clear();
  loads_.clear();
  load_stamp_ns_ = 0;
}

std::map<std::string, Inputs::Heat> Inputs::heat() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, Heat> out;
  for (const auto& [name, l] : loads_) out[name] = {l.rms.rms(), l.present.rms()};
  return out;
}

bool Inputs::on_frame(std::int64_t stamp_ns, hardware::RgbdFrame frame) {
  std::lock_guard lock(mutex_);
  if (!rig_) return false;
  const JointSample* s = nullptr;
  for (auto it = samples_.rbegin(); it != samples_.rend(); ++it) {
    if (it->stamp_ns <= stamp_ns) {
      s = &*it;
      break;
    }
  }
  if (s == nullptr) return false;
  CameraFrame f;
  f.stamp_ns = stamp_ns;
  f.frame = std::move(frame);
  f.base_T_optical = rig_->camera_in_base(rig_->q(s->joints));
  f.world_T_optical = rig_->base_in_world(s->odometry) * f.base_T_optical;
  frames_.push_back(std::move(f));
  while (frames_.size() > buffers_.frames) frames_.pop_front();
  return true;
}

std::optional<JointSample> Inputs::latest_sample() const {
  std::lock_guard lock(mutex_);
  if (samples_.empty()) return std::nullopt;
  JointSample s = samples_.back();
  if (odometry_) s.odometry = *odometry_;
  return s;
}

std::vector<CameraFrame> Inputs::frames_since(std::int64_t since_ns) const {
  std::lock_guard lock(mutex_);
  std::vector<CameraFrame> out;
  for (const CameraFrame& f : frames_) {
    if (f.stamp_ns > since_ns) out.push_back(f);
  }
  return out;
}

std::optional<CameraFrame> Inputs::averaged_view(std::int64_t since_ns, int count) const {
  if (count < 1) return std::nullopt;
  std::vector<CameraFrame> frames;
  {
    // Copies only the frames averaged (each is 1.5 MB at 640 x 480), once enough have come.
    std::lock_guard lock(mutex_);
    const auto newer = std::count_if(frames_.begin(), frames_.end(),
                                     [&](const CameraFrame& f) { return f.stamp_ns > since_ns; });
    if (newer < count) return std::nullopt;
    frames.assign(frames_.end() - count, frames_.end());
  }
  DepthAverager averager(static_cast<std::size_t>(count));
  for (const CameraFrame& f : frames) averager.add(f.frame);
  CameraFrame out = frames.back();
  out.frame = averager.average();
  return out;
}

std::optional<CameraFrame> Inputs::newest_frame(std::int64_t since_ns) const {
  std::lock_guard lock(mutex_);
  if (frames_.empty() || frames_.back().stamp_ns <= since_ns) return std::nullopt;
  return frames_.back();
}

std::int64_t Inputs::newest_stamp() const {
  std::lock_guard lock(mutex_);
  return frames_.empty() ? 0 : frames_.back().stamp_ns;
}

std::optional<hardware::CameraIntrinsics> Inputs::intrinsics() const {
  std::lock_guard lock(mutex_);
  if (frames_.empty() || frames_.back().frame.intrinsics.fx <= 0.0 || frames_.back().frame.intrinsics.fy <= 0.0)
    return std::nullopt;
  return frames_.back().frame.intrinsics;
}

std::optional<PlanReply> Inputs::plan(std::uint32_t request) const {
  std::lock_guard lock(mutex_);
  const auto it = plans_.find(request);
  if (it == plans_.end()) return std::nullopt;
  return it->second;
}

std::optional<MotionReply> Inputs::trajectory(std::uint32_t request) const {
  std::lock_guard lock(mutex_);
  const auto it = trajectories_.find(request);
  if (it == trajectories_.end()) return std::nullopt;
  return it->second;
}

std::optional<MotionReply> Inputs::nav(std::uint32_t request) const {
  std::lock_guard lock(mutex_);
  const auto it = navs_.find(request);
  if (it == navs_.end()) return std::nullopt;
  return it->second;
}

bool Inputs::safety_running() const {
  std::lock_guard lock(mutex_);
  return safety_ && safety_->running;
}

Outcome Inputs::health(Clock::time_point mission_started, bool uses_nav, Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  // A service not heard yet when the mission began (a stack just started: its status or the
  // joint states not matched yet) is waited for, liveness.service_lost at most.
  const bool starting = seconds_between(mission_started, now) < liveness_.service_lost;
  if (!safety_) {
    return starting ? Outcome::running() : Outcome::failed("no safety state from the safety service");
  }
  if (!safety_->running) {
    std::string causes;
    for (const auto& c : safety_->causes) causes += (causes.empty() ? "" : ", ") + c;
    return Outcome::failed("safety stop" + (causes.empty() ? "" : " (" + causes + ")"));
  }
  if (joints_seen_ == Clock::time_point{}) {
    if (starting) return Outcome::running();
    return Outcome::failed("no joint state from the robot service (never heard)");
  }
  const auto lost = [&](const std::string& service) {
    const auto seen = services_seen_.find(service);
    return seen == services_seen_.end() || seconds_between(seen->second, now) > liveness_.service_lost;
  };
  // Joint states late while the robot service's status still beats: a loaded machine delays
  // the 1 kHz stream by a second now and then (safety, watching the status, sees the robot
  // alive). The mission waits, deciding nothing on stale joints, instead of aborting a drilling
  // half done; joints silent for service_lost, or the robot's status silent too, end it.
  const double joints_age = seconds_between(joints_seen_, now);
  if (joints_age > liveness_.joints_lost) {
    const bool robot_lost = lost(liveness_.robot_service);
    if (joints_age > liveness_.service_lost || robot_lost) {
      std::ostringstream why;
      why << "no joint state from the robot service (lost: none for " << std::fixed << std::setprecision(1)
          << joints_age << " s" << (robot_lost ? ", its status silent too)" : ")");
      return Outcome::failed(why.str());
    }
    return Outcome::running();
  }
  if (services_seen_.count("planner") == 0 && starting) return Outcome::running();
  if (lost("planner")) return Outcome::failed("the planner service is lost");
  if (uses_nav && lost("nav")) return Outcome::failed("the nav service is lost");
  return Outcome::succeeded();
}

}  // namespace concert::drill
