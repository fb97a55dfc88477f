#pragma once
// The drill adapter's conversions between the core's plain types and the messages: the
// mission's status and report out, the planner's requests out and answers in, odometry in.

#include <Eigen/Core>

#include <cstdint>

#include "drill.h"
#include "nav.h"
#include "planning.h"
#include "system.h"
#include "robot.h"
#include "drill/mission_tree.hpp"
#include "drill/plan_exchange.hpp"

namespace concert::drill::dds {

/// The mission's status message from a tree's status and report.
msg::DrillStatus to_msg(std::uint32_t mission_id, const MissionStatus& status, const MissionReport& report);

/// The planner's answer as the core keeps it; a state or failure this build does not know is
/// taken as a failure.
PlanReply to_core(const msg::PlanResult& r);
/// A request as the planner takes it, stamped now.
msg::PlanRequest to_msg(const PlanAsk& a);

/// The robot's word on a trajectory, nav's on a goal, the safety state, as the core reads them.
MotionReply to_core(const msg::TrajectoryStatus& s);
MotionReply to_core(const msg::NavStatus& s);
SafetyWord to_core(const msg::SafetyState& s);

/// x, y, yaw of an odometry message.
Eigen::Vector3d odometry_of(const msg::Odometry& o);

}  // namespace concert::drill::dds
