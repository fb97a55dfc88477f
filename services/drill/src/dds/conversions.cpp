#include "dds/conversions.hpp"

#include <array>
#include <utility>

#include "concert/common/clock.hpp"
#include "concert/common/enum_map.hpp"
#include "concert/model/dds/pose.hpp"

namespace concert::drill::dds {

namespace {

// The mission's, areas' and holes' states and their wire twins, one row each.
constexpr EnumMap kMissionStates{std::array{
    std::pair{MissionState::kIdle, msg::DRILL_IDLE},
    std::pair{MissionState::kRunning, msg::DRILL_RUNNING},
    std::pair{MissionState::kSucceeded, msg::DRILL_SUCCEEDED},
    std::pair{MissionState::kFailed, msg::DRILL_FAILED},
    std::pair{MissionState::kAborted, msg::DRILL_ABORTED},
}};
constexpr EnumMap kAreaStates{std::array{
    std::pair{AreaState::kPending, msg::AREA_PENDING},
    std::pair{AreaState::kActive, msg::AREA_ACTIVE},
    std::pair{AreaState::kDone, msg::AREA_DONE},
    std::pair{AreaState::kFailed, msg::AREA_FAILED},
    std::pair{AreaState::kSkipped, msg::AREA_SKIPPED},
}};
constexpr EnumMap kHoleStates{std::array{
    std::pair{HoleState::kPending, msg::HOLE_PENDING},
    std::pair{HoleState::kDrilled, msg::HOLE_DRILLED},
    std::pair{HoleState::kFailed, msg::HOLE_FAILED},
    std::pair{HoleState::kSkipped, msg::HOLE_SKIPPED},
}};
constexpr EnumMap kReaches{std::array{
    std::pair{Reach::kUnknown, msg::REACH_UNKNOWN},
    std::pair{Reach::kReachable, msg::REACH_REACHABLE},
    std::pair{Reach::kUnreachable, msg::REACH_UNREACHABLE},
}};

// The planner's states and failures and their wire twins, one row each.
constexpr EnumMap kPlanStates{std::array{
    std::pair{PlanState::kPlanning, msg::PLAN_PLANNING},
    std::pair{PlanState::kPlanned, msg::PLAN_PLANNED},
    std::pair{PlanState::kExecuting, msg::PLAN_EXECUTING},
    std::pair{PlanState::kSucceeded, msg::PLAN_SUCCEEDED},
    std::pair{PlanState::kFailed, msg::PLAN_FAILED},
}};
constexpr EnumMap kPlanFailures{std::array{
    std::pair{PlanFailure::kOk, msg::PLAN_OK},
    std::pair{PlanFailure::kNoModel, msg::PLAN_NO_MODEL},
    std::pair{PlanFailure::kStaleModel, msg::PLAN_STALE_MODEL},
    std::pair{PlanFailure::kInvalidRequest, msg::PLAN_INVALID_REQUEST},
    std::pair{PlanFailure::kInvalidStart, msg::PLAN_INVALID_START},
    std::pair{PlanFailure::kUnreachable, msg::PLAN_UNREACHABLE},
    std::pair{PlanFailure::kNoPath, msg::PLAN_NO_PATH},
    std::pair{PlanFailure::kExecutionAborted, msg::PLAN_EXECUTION_ABORTED},
}};

}  // namespace

MotionReply to_core(const msg::TrajectoryStatus& s) {
  switch (s.state()) {
    case msg::TRAJECTORY_EXECUTING:
      return {Progress::kRunning, {}, s.reason()};
    case msg::TRAJECTORY_SUCCEEDED:
      return {Progress::kSucceeded, {}, s.reason()};
    case msg::TRAJECTORY_REFUSED:
      return {Progress::kFailed, "refused", s.reason()};
    case msg::TRAJECTORY_ABORTED:
      break;
  }
  return {Progress::kFailed, "aborted", s.reason()};
}

MotionReply to_core(const msg::NavStatus& s) {
  switch (s.state()) {
    case msg::NAV_REACHED:
      return {Progress::kSucceeded, {}, s.reason()};
    case msg::NAV_FAILED:
      return {Progress::kFailed, "failed", s.reason()};
    case msg::NAV_CANCELLED:
      return {Progress::kFailed, "cancelled", s.reason()};
    case msg::NAV_REFUSED:
      return {Progress::kFailed, "refused", s.reason()};
    case msg::NAV_IDLE:
    case msg::NAV_PLANNING:
    case msg::NAV_FOLLOWING:
      break;
  }
  return {Progress::kRunning, {}, s.reason()};
}

SafetyWord to_core(const msg::SafetyState& s) { return {s.mode() == msg::SAFETY_RUNNING, s.causes()}; }

Eigen::Vector3d odometry_of(const msg::Odometry& o) { return {o.x(), o.y(), o.yaw()}; }

PlanReply to_core(const msg::PlanResult& r) {
  PlanReply out;
  out.request_id = r.request_id();
  // A state this build does not know is a failure, never taken for progress.
  out.state = kPlanStates.from(r.state()).value_or(PlanState::kFailed);
  out.failure = kPlanFailures.from(r.failure()).value_or(PlanFailure::kInvalidRequest);
  out.reason = r.reason();
  out.path.names = r.joint_names();
  out.path.samples.reserve(r.trajectory().size());
  for (const msg::TrajectorySample& t : r.trajectory()) out.path.samples.push_back({t.time(), t.position(), t.velocity()});
  return out;
}

msg::PlanRequest to_msg(const PlanAsk& a) {
  msg::PlanRequest r;
  r.request_id(a.request_id);
  r.model_version(a.model_version);
  r.stamp_ns(now_ns());  // when this copy is sent (a resend is stamped anew)
  r.source(a.source);
  r.end_effector(a.end_effector);
  for (const Eigen::Isometry3d& g : a.goals) r.goals().push_back(model::dds::to_pose_msg(g));
  r.execute(a.execute);
  r.start_names(a.start_names);
  r.start_position(a.start_position);
  r.camera_distance(a.camera_distance);
  r.view_slant(a.view_slant);
  r.view_near(a.view_near);
  r.fixed_base(a.fixed_base);
  r.environment_padding(a.environment_padding);
  r.base_travel(a.base_travel);
  r.tip_distance(a.tip_distance);
  r.tip_reach(a.tip_reach);
  r.contact_force(a.contact_force);
  r.arm_home(a.home);
  if (a.odom_in_map) r.odom_in_map({a.odom_in_map->x(), a.odom_in_map->y(), a.odom_in_map->z()});
  return r;
}

msg::DrillStatus to_msg(std::uint32_t mission_id, const MissionStatus& status,
                        const MissionReport& report) {
  msg::DrillStatus out;
  out.mission_id(mission_id);
  out.stamp_ns(now_ns());
  out.mission(report.mission);
  out.state(kMissionStates.to(status.state).value_or(msg::DRILL_FAILED));
  out.active(status.active);
  out.area(static_cast<std::uint32_t>(status.area));
  out.hole(static_cast<std::uint32_t>(status.hole));
  out.reason(!report.reason.empty() ? report.reason : status.reason);
  for (const AreaReport& a : report.areas) {
    msg::DrillArea area;
    area.name(a.name);
    area.state(kAreaStates.to(a.state).value_or(msg::AREA_FAILED));
    area.reason(a.reason);
    area.frame(model::dds::to_pose_msg(a.located.frame));
    area.time_approach(a.times.approach);
    area.time_detect(a.times.detect);
    area.time_survey(a.times.survey);
    area.time_place(a.times.place);
    for (const HoleReport& h : a.holes) {
      msg::DrillHole hole;
      hole.label(h.point.label);
      hole.frame(model::dds::to_pose_msg(h.point.frame));
      hole.state(kHoleStates.to(h.state).value_or(msg::HOLE_FAILED));
      hole.reason(h.reason);
      hole.reach(kReaches.to(h.reach.reach).value_or(msg::REACH_UNKNOWN));
      hole.reach_reason(h.reach.why);
      hole.time_align(h.times.align);
      hole.time_drill(h.times.drill);
      hole.time_retract(h.times.retract);
      area.holes().push_back(hole);
    }
    out.areas().push_back(area);
  }
  out.time_navigate(report.times.navigate);
  out.time_plan(report.times.plan);
  out.time_execute(report.times.execute);
  out.time_drill(report.times.drill);
  out.time_total(report.times.total);
  out.holes_drilled(static_cast<std::uint32_t>(report.holes_drilled()));
  out.holes_marked(static_cast<std::uint32_t>(report.holes_marked()));
  return out;
}

}  // namespace concert::drill::dds
