#include "planner/request.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <sstream>
#include <stdexcept>

#include "concert/mobile_base/map_frame.hpp"

namespace concert::planner {
namespace {

// The full start state a request gives (base_x, base_y, base_yaw and the joints by name).
// Throws naming what is missing or unknown.
Eigen::VectorXd given_start(const PlanningModel& model, const ClientRequest& request) {
  const auto& names = request.start_names;
  const auto& values = request.start_position;
  if (names.size() != values.size()) {
    throw PlannerError("start state has " + std::to_string(names.size()) + " names and " +
                       std::to_string(values.size()) + " positions");
  }
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  std::vector<std::string> joints;
  std::vector<double> positions;
  constexpr std::array<const char*, 3> kBase{"base_x", "base_y", "base_yaw"};
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!std::isfinite(values[i])) throw PlannerError("start state: '" + names[i] + "' is not finite");
    const auto b = std::find(kBase.begin(), kBase.end(), names[i]);
    if (b != kBase.end()) {
      base[b - kBase.begin()] = values[i];
    } else {
      joints.push_back(names[i]);
      positions.push_back(values[i]);
    }
  }
  return model.full_from_named(joints, positions, base);
}

// The start state, or why there is none to execute from (empty when there is one).
std::string find_start(const ClientRequest& request, const PlanningModel& model, const MeasuredRobot& robot,
                       Eigen::VectorXd& start) {
  const Eigen::Vector3d pose = robot.odometry.value_or(Eigen::Vector3d::Zero());
  const auto& js = robot.joints;
  try {
    if (!request.start_names.empty()) {
      start = given_start(model, request);
      if (request.execute) return "a request with a start state cannot be executed (the robot is not there)";
    } else if (js && js->model_version == model.version()) {
      start = model.full_from_named(js->names, js->positions, pose);
    } else if (request.execute) {
      return js ? "the robot runs model version " + std::to_string(js->model_version) + ", the planner " +
                      std::to_string(model.version())
                : "no joint state from the robot service yet (needed to execute)";
    } else {
      // Planning only, without a robot of this model: the model's zero posture where odometry is.
      start = Eigen::VectorXd::Zero(model.full_dof());
      start.head<3>() = pose;
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

}  // namespace

PreparedRequest prepare_request(const ClientRequest& request, const PlanningModel* model,
                                const MeasuredRobot& robot, const FrameKnowledge& frame) {
  PreparedRequest out;
  out.plan = request.plan;
  if (model != nullptr && request.plan.model_version == model->version()) {
    if (std::string why = find_start(request, *model, robot, out.start); !why.empty()) {
      out.refusal = Status::kInvalidStart;
      out.reason = std::move(why);
      return out;
    }
  }

  // Into the map frame, where the world is (the identity until nav localises the base), or where
  // the client measured the odometry frame to be.
  out.map_T_odom = frame.map_T_odom;
  if (const std::vector<double>& c = request.odom_in_map; !c.empty()) {
    const Eigen::Vector3d given(c[0], c.size() > 1 ? c[1] : 0.0, c.size() > 2 ? c[2] : 0.0);
    std::ostringstream note;
    if (c.size() != 3 || !given.allFinite()) {
      note << "odom_in_map needs 3 finite values (x, y, yaw), got " << c.size();
      out.refusal = Status::kInvalidRequest;
      out.reason = note.str();
      return out;
    }
    if (frame.map_from_sensors) {
      note << "the client's odometry frame (" << given.x() << ", " << given.y() << ", " << given.z()
           << ") not used: the map comes from the sensors, placed with nav's";
    } else {
      out.map_T_odom = given;
      note << "planned in the map, odometry frame at (" << given.x() << ", " << given.y() << ", " << given.z()
           << ") as the client measured it";
    }
    out.frame_note = note.str();
  }
  const Eigen::Isometry3d map_from_odom = mobile_base::isometry(out.map_T_odom);
  for (Goal& g : out.plan.goals) g.area = map_from_odom * g.area;
  out.yaw_offset = -out.map_T_odom.z();
  if (out.start.size() >= 3) {
    const double odom_yaw = out.start(2);
    out.start.head<3>() = mobile_base::compose(out.map_T_odom, out.start.head<3>());
    out.yaw_offset = odom_yaw - out.start(2);
  }
  return out;
}

Trajectory to_odometry_frame(Trajectory trajectory, const Eigen::Vector3d& map_T_odom, double yaw_offset) {
  const double c = std::cos(map_T_odom.z()), s = std::sin(map_T_odom.z());
  for (TrajectoryPoint& p : trajectory.points) {
    if (p.q.size() < 3) continue;
    const double dx = p.q(0) - map_T_odom.x(), dy = p.q(1) - map_T_odom.y();
    p.q(0) = c * dx + s * dy;
    p.q(1) = -s * dx + c * dy;
    p.q(2) += yaw_offset;
    if (p.qd.size() >= 2) {
      const double vx = p.qd(0), vy = p.qd(1);
      p.qd(0) = c * vx + s * vy;
      p.qd(1) = -s * vx + c * vy;
    }
  }
  return trajectory;
}

std::string describe(const PlanResult& result, const PreparedRequest& prepared, const FrameKnowledge& frame) {
  std::ostringstream line;
  line << "planner: request " << result.request_id << ": " << to_string(result.status)
       << (result.reason.empty() ? "" : " (" + result.reason + ")") << (result.note.empty() ? "" : "; " + result.note);
  if (!prepared.frame_note.empty()) {
    line << "; " << prepared.frame_note;
  } else if (frame.localised) {
    const Eigen::Vector3d& m = prepared.map_T_odom;
    line << "; planned in the map, odometry frame at (" << m.x() << ", " << m.y() << ", " << m.z() << ")";
  }
  for (const GoalResult& g : result.goals) {
    if (g.status != Status::kSucceeded) continue;
    line << "; goal " << g.index << " in " << static_cast<int>(1e3 * (g.nspg_seconds + g.plan_seconds)) << " ms ("
         << g.path_method << (g.load.empty() ? "" : "; load " + g.load)
         << (g.drives.empty() ? "" : "; drives " + g.drives) << ")";
  }
  return line.str();
}

}  // namespace concert::planner
