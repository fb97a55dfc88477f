#pragma once
// What the drill has measured and heard, kept for its control thread: joint states with the
// odometry (decimated, a couple of seconds), the drill camera's frames posed with the joint
// state at their stamp, the planner's answers, the robot's and nav's word on what the drill
// sent, the safety state and when the other services were last heard. Filled by the adapter's
// callbacks (other threads), read by the control thread; thread-safe. Plain C++, no DDS: the
// adapter converts the messages, this decides what is kept and whether the robot may move.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "concert/model/limits.hpp"
#include "drill/drill_rig.hpp"
#include "drill/params.hpp"
#include "drill/paths.hpp"
#include "drill/plan_exchange.hpp"
#include "drill/ports.hpp"

namespace concert::drill {

/// One frame of the drill camera, posed with the joint state and odometry at its stamp.
struct CameraFrame {
  std::int64_t stamp_ns{0};  ///< robot clock
  hardware::RgbdFrame frame;
  Eigen::Isometry3d world_T_optical{Eigen::Isometry3d::Identity()};  ///< odometry frame
  Eigen::Isometry3d base_T_optical{Eigen::Isometry3d::Identity()};
};

class Inputs {
 public:
  using Clock = std::chrono::steady_clock;

  Inputs(Params::Buffers buffers, Params::Liveness liveness);

  /// A joint state (robot clock `stamp_ns`) heard at `now`: kept at most one per
  /// Buffers::sample_step, with the odometry last heard. Every state's `efforts` (as many as
  /// names, else none) feed each joint's thermal load (heat()).
  void on_joints(std::int64_t stamp_ns, JointPositions joints, Clock::time_point now,
                 const std::vector<double>& efforts = {});
  /// The wheel odometry (x, y, yaw), newest.
  void on_odometry(const Eigen::Vector3d& odometry);
  /// A service's status heard at `now`; `stopped`: it said it stops (no longer counted as alive).
  void on_service(const std::string& service, bool stopped, Clock::time_point now);
  void on_safety(SafetyWord safety);
  /// The planner's answer, merged into the last one for its request (merge_reply).
  void on_plan(const PlanReply& reply);
  void on_trajectory(std::uint32_t request, MotionReply reply);
  void on_nav(std::uint32_t request, MotionReply reply);

  /// The model's rig (null: the model cannot drill); the frames kept so far are dropped (posed
  /// with another model).
  void set_rig(std::shared_ptr<const DrillRig> rig);
  /// A camera frame at `stamp_ns`: posed with the newest joint sample not after it and kept
  /// (Buffers::frames); false when not kept (no rig, no sample old enough).
  bool on_frame(std::int64_t stamp_ns, hardware::RgbdFrame frame);

  /// The newest joint sample with the newest odometry.
  [[nodiscard]] std::optional<JointSample> latest_sample() const;
  /// Frames newer than `since_ns`, oldest first.
  [[nodiscard]] std::vector<CameraFrame> frames_since(std::int64_t since_ns) const;
  /// The newest `count` frames' depth averaged, with the newest's pose; none while fewer than
  /// `count` newer than `since_ns` have come.
  [[nodiscard]] std::optional<CameraFrame> averaged_view(std::int64_t since_ns, int count) const;
  /// The newest frame, when newer than `since_ns`.
  [[nodiscard]] std::optional<CameraFrame> newest_frame(std::int64_t since_ns) const;
  /// The newest frame's stamp, 0 without frames: what comes after it was taken after now.
  [[nodiscard]] std::int64_t newest_stamp() const;
  /// The newest frame's intrinsics, when it has a focal length.
  [[nodiscard]] std::optional<hardware::CameraIntrinsics> intrinsics() const;

  /// What a joint's drive has carried, from the efforts the robot reports: the RMS over the
  /// thermal window (model::ThermalLoad, the safety layer's rule on the same stream) and the
  /// load it holds now (the same over kPresentWindow) [N m].
  struct Heat {
    double rms{0.0};
    double present{0.0};
  };
  /// The window of Heat::present [s]: long enough to average a settle's oscillation out, short
  /// against the thermal window.
  static constexpr double kPresentWindow = 0.5;
  /// Each joint's heat since the rig was set (a new model starts cold, as safety's does).
  [[nodiscard]] std::map<std::string, Heat> heat() const;

  [[nodiscard]] std::optional<PlanReply> plan(std::uint32_t request) const;
  [[nodiscard]] std::optional<MotionReply> trajectory(std::uint32_t request) const;
  [[nodiscard]] std::optional<MotionReply> nav(std::uint32_t request) const;

  /// Whether the robot may move at `now` for a mission started at `mission_started`: safety
  /// RUNNING, joint states fresh, the planner (and nav when `uses_nav`) heard within
  /// Liveness::service_lost. A service not heard yet is waited for (kRunning) until
  /// service_lost after the mission's start, then it fails the mission, naming it.
  [[nodiscard]] Outcome health(Clock::time_point mission_started, bool uses_nav, Clock::time_point now) const;
  /// The safety service's last word was RUNNING (false before any word).
  [[nodiscard]] bool safety_running() const;

 private:
  Params::Buffers buffers_;
  Params::Liveness liveness_;
  mutable std::mutex mutex_;
  std::deque<JointSample> samples_;
  struct Load {
    model::ThermalLoad rms{model::kThermalWindow};
    model::ThermalLoad present{kPresentWindow};
  };
  std::map<std::string, Load> loads_;
  std::int64_t load_stamp_ns_{0};
  std::optional<Eigen::Vector3d> odometry_;
  Clock::time_point joints_seen_{};
  std::map<std::string, Clock::time_point> services_seen_;
  std::optional<SafetyWord> safety_;
  std::map<std::uint32_t, PlanReply> plans_;
  std::map<std::uint32_t, MotionReply> trajectories_;
  std::map<std::uint32_t, MotionReply> navs_;
  std::shared_ptr<const DrillRig> rig_;
  std::deque<CameraFrame> frames_;
};

}  // namespace concert::drill
