#include "robot_node.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/model/robot_model.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "robot_conversions.hpp"

namespace concert::robot::dds {

namespace cdds = concert::dds;

RobotNode::RobotNode(cdds::Participant& participant, RobotCore& core, NodeParams params, ModelHook before_model)
    : participant_(participant),
      core_(core),
      params_(std::move(params)),
      before_model_(std::move(before_model)),
      status_(participant, params_.service_name),
      joint_state_(participant, cdds::topics::joint_state),
      odometry_(participant, cdds::topics::odometry),
      wrench_(participant, cdds::topics::ee_wrench),
      scan_(participant, cdds::topics::esc_scan),
      trajectory_status_(participant, cdds::topics::trajectory_status),
      safety_watchdog_(params_.safety_timeout, SafetyWatchdog::Clock::now()) {
  status_.report(msg::SERVICE_STARTING, 0, "waiting for a robot model");
  model_reader_ = std::make_unique<cdds::Reader<msg::RobotModel>>(
      participant, cdds::topics::robot_model, [this](const msg::RobotModel& m, const auto&) { on_model(m); });
  joint_reader_ = std::make_unique<cdds::Reader<msg::JointCommand>>(
      participant, cdds::topics::joint_command,
      [this](const msg::JointCommand& c, const auto&) { guarded("joint command", [&] { core_.command_joints(to_core(c)); }); });
  cartesian_reader_ = std::make_unique<cdds::Reader<msg::CartesianImpedanceCommand>>(
      participant, cdds::topics::cartesian_command, [this](const msg::CartesianImpedanceCommand& c, const auto&) {
        guarded("Cartesian command", [&] { core_.command_cartesian(to_core(c)); });
      });
  base_reader_ = std::make_unique<cdds::Reader<msg::BaseVelocityCommand>>(
      participant, cdds::topics::base_velocity, [this](const msg::BaseVelocityCommand& c, const auto&) {
        guarded("base command", [&] { core_.command_base(to_core(c)); });
      });
  if (safety_watchdog_.required()) check_safety_silence();  // holds until the safety service is heard
  safety_reader_ = std::make_unique<cdds::Reader<msg::SafetyState>>(
      participant, cdds::topics::safety_state, [this](const msg::SafetyState& s, const auto&) { on_safety(s); });
  trajectory_reader_ = std::make_unique<cdds::Reader<msg::JointTrajectoryCommand>>(
      participant, cdds::topics::trajectory_command,
      [this](const msg::JointTrajectoryCommand& c, const auto&) { on_trajectory(c); });
}

std::string tool_end_effector(const msg::RobotModel& m) {
  try {
    return model::RobotModel::build(model::dds::to_description(m))->tool().frame;
  } catch (const std::exception&) {
    return "";  // no parsable description or no arm tool: the core's own choice
  }
}

namespace {
/// The tool end-effector and the limits table of a model message, from one parse: "" and an
/// empty table where the description does not parse (the core's own end-effector, the drives'
/// rated peaks), "" alone where it has no arm tool.
}  // namespace

void RobotNode::on_safety(const msg::SafetyState& s) {
  const bool stopped = s.mode() == msg::SAFETY_STOPPED;
  std::string causes;
  for (const auto& c : s.causes()) {
    causes += (causes.empty() ? "" : "; ") + c;
  }
  std::lock_guard lock(safety_mutex_);
  safety_watchdog_.heard(SafetyWatchdog::Clock::now());
  const bool was = core_.safety_stopped();
  core_.set_safety_stop(stopped, causes);
  if (safety_silent_) {
    safety_silent_ = false;
    holding_ = stopped ? "safety stop: holding (" + causes + "; the safety service heard again)" : "";
    status_.note(stopped ? holding_ : "safety stop released (the safety service heard again, RUNNING)");
  } else if (stopped != was) {
    holding_ = stopped ? "safety stop: holding (" + causes + ")" : "";
    status_.note(stopped ? holding_ : "safety stop released");
  }
}

void RobotNode::check_safety_silence() {
  std::lock_guard lock(safety_mutex_);
  if (safety_silent_) return;
  if (auto why = safety_watchdog_.silence(SafetyWatchdog::Clock::now())) {
    safety_silent_ = true;
    core_.set_safety_stop(true, *why);
    holding_ = "safety stop: holding (" + *why + ")";
    status_.note(holding_);
  }
}

void RobotNode::on_trajectory(const msg::JointTrajectoryCommand& c) {
  try {
    {
      std::lock_guard lock(mutex_);
      previous_request_ = last_request_;
      last_request_ = {c.request_id(), c.model_version(), c.source()};
    }
    core_.command_trajectory(to_core(c));
  } catch (const std::exception& e) {
    ++refused_;
    {
      std::lock_guard lock(mutex_);
      last_error_ = e.what();
    }
    msg::TrajectoryStatus s;
    s.request_id(c.request_id());
    s.model_version(static_cast<uint32_t>(core_.model_version()));
    s.stamp_ns(now_ns());
    s.source(c.source());
    s.state(msg::TRAJECTORY_REFUSED);
    s.reason(e.what());
    trajectory_status_.write(s);
    status_.refused(std::string("trajectory refused: ") + e.what());
  }
}

RobotNode::~RobotNode() {
  // Readers first: their callbacks use the core and the status writer.
  trajectory_reader_.reset();
  safety_reader_.reset();
  base_reader_.reset();
  cartesian_reader_.reset();
  joint_reader_.reset();
  model_reader_.reset();
}

template <class F> void RobotNode::guarded(const std::string& what, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    ++refused_;
    {
      std::lock_guard lock(mutex_);
      last_error_ = e.what();
    }
    status_.refused(what + " refused: " + e.what());
  }
}

void RobotNode::on_model(const msg::RobotModel& m) {
  // The same model again (a restarted modelgen republishes the running one): keep running it.
  if (core_.ready() && core_.model_version() == m.version() &&
      status_.model().hash == m.content_hash())
    return;
  // The model as every service builds it; the core reads its tool, legs and limits table
  // (the legs' continuous torques: their drives' torque foldback). A message without chains
  // that does not build (a bare URDF without a limits table: hand-made models, tests) is run as
  // a URDF.
  apply(m.version(), m.content_hash(), [&] {
    std::shared_ptr<const model::RobotModel> built;
    try {
      built = model::RobotModel::build(model::dds::to_description(m));
    } catch (const std::exception& e) {
      if (m.chains().empty()) {
        core_.check_newer(m.version(), "model version " + std::to_string(m.version()));
        if (before_model_) before_model_(model::dds::to_description(m));
        core_.set_model(m.urdf(), m.version());
        return model::LimitsTable{};
      }
      throw ModelMismatchError(e.what());
    }
    // What the core would refuse first is checked before the hook prepares anything for it.
    core_.check_newer(m.version(), "model version " + std::to_string(m.version()));
    if (before_model_) before_model_(built->description());
    core_.set_model(built);
    return built->limits();
  });
}

void RobotNode::apply_model(const std::string& urdf, std::uint64_t version,
                            const std::string& end_effector_frame,
                            const std::string& content_hash, const model::LimitsTable& limits) {
  apply(version, content_hash, [&] {
    core_.set_model(urdf, version, end_effector_frame, limits);
    return limits;
  });
}

template <class Install>
void RobotNode::apply(std::uint64_t version, const std::string& content_hash, Install&& install) {
  try {
    status_.report(msg::SERVICE_RECONFIGURING, status_.model_version(),
                   "reconfiguring to model version " + std::to_string(version));
    const model::LimitsTable limits = install();
    {
      std::lock_guard lock(mutex_);
      limits_ = limits;
      applied_ = {static_cast<uint32_t>(version), content_hash};
    }
    status_.report(msg::SERVICE_READY,
                   concert::dds::ModelId{static_cast<uint32_t>(version), content_hash},
                   "ready at model version " + std::to_string(version));
    // Still holding for the safety layer: say so again, as the message the heartbeat repeats
    // (a reader that matched after the first saying, e.g. after a restart, hears it).
    std::lock_guard lock(safety_mutex_);
    if (!holding_.empty()) status_.note(holding_);
  } catch (const std::exception& e) {
    ++refused_;
    {
      std::lock_guard lock(mutex_);
      last_error_ = e.what();
    }
    // The last good model keeps running if the hardware still matches it.
    status_.report(core_.ready() ? msg::SERVICE_READY : msg::SERVICE_ERROR,
                   static_cast<uint32_t>(core_.model_version()), e.what());
    status_.refused(std::string("model version ") + std::to_string(version) +
                    " refused: " + e.what());
    // Also in the service's log: the heartbeat's status soon says only that the robot waits.
    std::cerr << "concert_robot: model version " << version << " refused: " << e.what() << "\n";
  }
}

void RobotNode::publish(const RobotState& s) {
  if (safety_watchdog_.required()) check_safety_silence();
  joint_state_.write(to_joint_state(s));
  if (s.has_base) {
    distance_ += std::hypot(s.odometry.x - last_x_, s.odometry.y - last_y_);
    last_x_ = s.odometry.x;
    last_y_ = s.odometry.y;
    if (cycles_ % static_cast<std::uint64_t>(std::max(1, params_.odometry_decimation)) == 0) {
      odometry_.write(to_odometry(s, distance_));
    }
  }
  if (!s.end_effector_frame.empty() &&
      cycles_ % static_cast<std::uint64_t>(std::max(1, params_.wrench_decimation)) == 0) {
    wrench_.write(to_wrench(s));
  }
  if (s.replaced_trajectory.sequence != 0 && s.replaced_trajectory.sequence != last_replaced_) {
    last_replaced_ = s.replaced_trajectory.sequence;
    publish_trajectory(s.replaced_trajectory, s.model_version);
  }
  const TrajectoryProgress& p = s.trajectory;
  const bool changed = p.sequence != last_sequence_ || p.state != last_state_;
  if (p.sequence != 0 &&
      (changed || (p.state == TrajectoryState::kExecuting &&
                   cycles_ % static_cast<std::uint64_t>(std::max(1, params_.trajectory_decimation)) == 0))) {
    publish_trajectory(p, s.model_version);
    last_sequence_ = p.sequence;
    last_state_ = p.state;
  }
  if (last_ready_ && !s.ready) {
    status_.report(msg::SERVICE_RECONFIGURING, static_cast<uint32_t>(s.model_version), s.message);
  } else if (!last_ready_ && s.ready && status_.state() != msg::SERVICE_READY) {
    // Ready again at a model applied while this thread had not yet seen the hardware change
    // (a hot swap on a loaded machine: the swap's model reports READY, then this thread its
    // "hardware changed" RECONFIGURING, which would otherwise stand for good with the robot
    // ready at the new model).
    concert::dds::ModelId applied;
    {
      std::lock_guard lock(mutex_);
      applied = applied_;
    }
    if (applied.version == s.model_version) status_.report(msg::SERVICE_READY, applied, s.message);
  }
  last_ready_ = s.ready;
  log_foldback(s);
  ++cycles_;
}

void RobotNode::log_foldback(const RobotState& s) {
  if (cycles_ % 50 != 0) return;  // a drive heats over seconds
  const auto fixed = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f", v);
    return std::string(text);
  };
  folded_.resize(s.joint_names.size(), false);
  std::lock_guard lock(mutex_);
  for (std::size_t h = 0; h < s.joint_names.size() && h < s.torque_limit.size(); ++h) {
    const model::JointLimits* row = limits_.find(s.joint_names[h]);
    if (row == nullptr || s.torque_limit[h] <= 0.0) continue;
    const double halfway = 0.5 * (row->peak_torque + row->continuous_torque);
    if (!folded_[h] && s.torque_limit[h] <= halfway) {
      folded_[h] = true;
      std::cerr << "concert_robot: " << row->name << " folds its torque back to "
                << fixed(s.torque_limit[h]) << " N m (peak " << fixed(row->peak_torque)
                << ", continuous " << fixed(row->continuous_torque)
                << "): its RMS torque over the thermal window nears the continuous torque\n";
    } else if (folded_[h] && s.torque_limit[h] >= row->peak_torque) {
      folded_[h] = false;
      std::cerr << "concert_robot: " << row->name << " back at its peak torque "
                << fixed(row->peak_torque) << " N m\n";
    }
  }
}

void RobotNode::publish_trajectory(const TrajectoryProgress& p, std::uint64_t model_version) {
  msg::TrajectoryStatus out;
  {
    std::lock_guard lock(mutex_);
    out.source(last_request_.id == p.request_id       ? last_request_.source
               : previous_request_.id == p.request_id ? previous_request_.source
                                                      : std::string{});
  }
  out.request_id(p.request_id);
  out.model_version(static_cast<uint32_t>(model_version));
  out.stamp_ns(now_ns());
  out.state(to_msg(p.state));
  out.reason(p.state == TrajectoryState::kAborted ? core_.describe(p) : std::string{});
  out.progress(p.progress);
  out.max_joint_error(p.max_joint_error);
  out.max_base_error(p.max_base_error);
  trajectory_status_.write(out);
  if (p.state == TrajectoryState::kAborted) {
    status_.note("trajectory " + std::to_string(p.request_id) + " aborted: " + out.reason());
  }
}

void RobotNode::publish_scan(const topology::EscScan& scan, const std::string& source) {
  scan_.write(topology::dds::to_msg(scan, ++scan_id_, now_ns(), source));
}

std::string RobotNode::last_error() const {
  std::lock_guard lock(mutex_);
  return last_error_;
}

}  // namespace concert::robot::dds
