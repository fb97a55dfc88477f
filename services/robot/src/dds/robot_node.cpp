#include "robot_node.hpp"

#include <chrono>
#include <cmath>

#include "concert/common/clock.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "robot_conversions.hpp"

namespace concert::robot::dds {

namespace cdds = concert::dds;

RobotNode::RobotNode(cdds::Participant& participant, RobotCore& core, NodeParams params)
    : participant_(participant),
      core_(core),
      params_(std::move(params)),
      status_(participant, params_.service_name),
      joint_state_(participant, cdds::topics::joint_state),
      odometry_(participant, cdds::topics::odometry),
      wrench_(participant, cdds::topics::ee_wrench),
      scan_(participant, cdds::topics::esc_scan) {
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
  safety_reader_ = std::make_unique<cdds::Reader<msg::SafetyState>>(
      participant, cdds::topics::safety_state, [this](const msg::SafetyState& s, const auto&) {
        const bool stopped = s.mode() == msg::SAFETY_STOPPED;
        std::string causes;
        for (const auto& c : s.causes()) {
          causes += (causes.empty() ? "" : "; ") + c;
        }
        const bool was = core_.safety_stopped();
        core_.set_safety_stop(stopped, causes);
        if (stopped != was) {
          status_.note(stopped ? "safety stop: holding (" + causes + ")" : "safety stop released");
        }
      });
}

RobotNode::~RobotNode() {
  // Readers first: their callbacks use the core and the status writer.
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
  const std::string ee = m.end_effectors().empty() ? std::string{} : m.end_effectors().front().frame();
  apply_model(m.urdf(), m.version(), ee, m.content_hash());
}

void RobotNode::apply_model(const std::string& urdf, std::uint64_t version,
                            const std::string& end_effector_frame,
                            const std::string& content_hash) {
  try {
    status_.report(msg::SERVICE_RECONFIGURING, status_.model_version(),
                   "reconfiguring to model version " + std::to_string(version));
    core_.set_model(urdf, version, end_effector_frame);
    status_.report(msg::SERVICE_READY,
                   concert::dds::ModelId{static_cast<uint32_t>(version), content_hash},
                   "ready at model version " + std::to_string(version));
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
  }
}

void RobotNode::publish(const RobotState& s) {
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
  if (last_ready_ && !s.ready) {
    status_.report(msg::SERVICE_RECONFIGURING, static_cast<uint32_t>(s.model_version), s.message);
  }
  last_ready_ = s.ready;
  ++cycles_;
}

void RobotNode::publish_scan(const topology::EscScan& scan, const std::string& source) {
  scan_.write(topology::dds::to_msg(scan, ++scan_id_, now_ns(), source));
}

std::string RobotNode::last_error() const {
  std::lock_guard lock(mutex_);
  return last_error_;
}

}  // namespace concert::robot::dds
