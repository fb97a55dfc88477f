#include "concert/ethercat/ethercat_hardware.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <set>

namespace concert::ethercat {

EthercatHardware::EthercatHardware(Link& link, ProcessDataCatalog process_data, MasterParams params)
    : master_(link, params), process_data_(std::move(process_data)) {
  report_ = master_.scan();
  image_ = master_.map_process_data(report_);
  for (const auto state : {esc::AlState::kPreOp, esc::AlState::kSafeOp}) master_.request_state(report_, state);
  // Drives expect outputs flowing (all disabled here) before OP.
  for (int i = 0; i < 10; ++i) master_.cycle(image_);
  master_.request_state(report_, esc::AlState::kOp);
}

void EthercatHardware::prepare_joints(const std::vector<std::pair<std::string, int32_t>>& joints) {
  {
    std::lock_guard lock(binding_mutex_);
    if (prepared_generation_ > 0 && joints == prepared_) return;
  }
  std::set<std::string> names;
  for (const auto& [name, robot_id] : joints) {
    if (!names.insert(name).second) throw hardware::HardwareError("joint '" + name + "' is listed twice");
  }
  // report_, image_'s layout and process_data_ are fixed from the constructor on: read here
  // from any thread.
  std::vector<Joint> bound;
  std::set<int32_t> boards;
  for (const auto& [name, robot_id] : joints) {
    const SlaveReport* found = nullptr;
    for (const SlaveReport& s : report_.slaves) {
      if (!s.sii.module || s.sii.robot_id != robot_id || robot_id < 0) continue;
      if (found) {
        throw hardware::HardwareError("joint '" + name + "': robot_id " + std::to_string(robot_id) +
                                      " is on two slaves, " + std::to_string(found->position) + " and " +
                                      std::to_string(s.position) + ": a board programmed twice");
      }
      found = &s;
    }
    if (!found) {
      std::string ids;
      for (const SlaveReport& s : report_.slaves) {
        if (s.sii.robot_id >= 0) ids += (ids.empty() ? "" : ", ") + std::to_string(s.sii.robot_id);
      }
      throw hardware::HardwareError("joint '" + name + "': no board with robot_id " + std::to_string(robot_id) +
                                    " on the ring (robot_ids there: " + ids + ")");
    }
    const std::string where = "joint '" + name + "': robot_id " + std::to_string(robot_id) + " is slave " +
                              std::to_string(found->position);
    const BoardProcessData* board = process_data_.find(found->slave.esc_type);
    const ProcessImageSlave* slave = image_.slave(found->position);
    if (!board || !slave || !board->output("position_ref")) {
      throw hardware::HardwareError(where + " (ESC type " + std::to_string(found->slave.esc_type) +
                                    "), which is no drive");
    }
    if (!boards.insert(found->position).second) {
      throw hardware::HardwareError(where + ", already bound to another joint");
    }
    try {
      DriveCodec codec(*board);
      // The codec's offsets come from the process data file, the slave's bytes from its SII:
      // a board whose process data is smaller would be written past.
      if (codec.output_bytes() > slave->output_bytes || codec.input_bytes() > slave->input_bytes) {
        throw hardware::HardwareError(where + ": its SII gives " + std::to_string(slave->output_bytes) +
                                      " bytes out and " + std::to_string(slave->input_bytes) + " in, a drive needs " +
                                      std::to_string(codec.output_bytes()) + " and " + std::to_string(codec.input_bytes()));
      }
      bound.push_back(Joint{name, static_cast<std::size_t>(slave - image_.slaves.data()), codec});
    } catch (const ProcessDataError& e) {
      throw hardware::HardwareError(where + ": " + e.what());
    }
  }
  Binding b;
  b.joints = std::move(bound);
  for (const Joint& j : b.joints) b.names.push_back(j.name);
  b.enabled.assign(b.joints.size(), false);
  std::optional<Binding> freed;
  std::lock_guard lock(binding_mutex_);
  // Another thread may have prepared the same binding meanwhile.
  if (prepared_generation_ > 0 && joints == prepared_) return;
  freed.swap(retired_);
  b.generation = ++prepared_generation_;
  prepared_ = joints;
  pending_ = std::move(b);
  mounted_generation_.store(pending_->generation, std::memory_order_release);
  has_pending_.store(true, std::memory_order_release);
}

void EthercatHardware::bind_joints(const std::vector<std::pair<std::string, int32_t>>& joints) {
  prepare_joints(joints);
  switch_prepared();
}

hardware::MountedHardware EthercatHardware::mounted() const {
  std::lock_guard lock(binding_mutex_);
  if (pending_) return {pending_->generation, pending_->names};
  return {generation_, names_};
}

bool EthercatHardware::switch_prepared() {
  // Locks only when a binding waits: the other threads' work under the lock (copies, frees)
  // does not delay the cycles in between.
  if (!has_pending_.load(std::memory_order_acquire)) return false;
  std::lock_guard lock(binding_mutex_);
  if (!pending_) return false;
  joints_.swap(pending_->joints);
  names_.swap(pending_->names);
  enabled_.swap(pending_->enabled);
  generation_ = pending_->generation;
  // A board of the old binding that the new one leaves out is told to stop: its last command
  // (maybe a torque) would otherwise stay in the outputs.
  for (const Joint& old : pending_->joints) {
    const bool kept = std::any_of(joints_.begin(), joints_.end(), [&](const Joint& j) { return j.slave == old.slave; });
    if (kept) continue;
    const ProcessImageSlave& s = image_.slaves[old.slave];
    old.codec.encode(hardware::DriveCommand{}, false,
                     std::span<uint8_t>(image_.outputs).subspan(s.output_offset, s.output_bytes));
  }
  retired_.swap(pending_);  // retired_ was emptied by prepare_joints(): nothing freed here
  pending_.reset();         // an empty optional after the swap above
  has_pending_.store(false, std::memory_order_release);
  return true;
}

void EthercatHardware::read(hardware::HardwareState& state) {
  const std::size_t n = joints_.size();
  state.time = time_;
  state.position.resize(n);
  state.velocity.resize(n);
  state.effort.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const ProcessImageSlave& s = image_.slaves[joints_[j].slave];
    const DriveFeedback f = joints_[j].codec.decode_feedback(
        std::span<const uint8_t>(image_.inputs).subspan(s.input_offset, s.input_bytes));
    state.position[j] = f.link_position;
    state.velocity[j] = f.velocity;
    state.effort[j] = f.torque;
  }
}

void EthercatHardware::write(const std::vector<hardware::DriveCommand>& commands) {
  if (commands.size() != joints_.size()) {
    throw hardware::HardwareError("ethercat: " + std::to_string(commands.size()) + " commands for " +
                                  std::to_string(joints_.size()) + " joints");
  }
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const ProcessImageSlave& s = image_.slaves[joints_[j].slave];
    enabled_[j] = true;
    joints_[j].codec.encode(commands[j], true,
                            std::span<uint8_t>(image_.outputs).subspan(s.output_offset, s.output_bytes));
  }
}

std::vector<std::pair<std::string, int32_t>> joint_robot_ids(const std::string& config_yaml) {
  std::vector<std::pair<std::string, int32_t>> out;
  YAML::Node root;
  try {
    root = YAML::Load(config_yaml);
  } catch (const YAML::Exception& e) {
    throw hardware::HardwareError("the model's controller configuration: " + std::string(e.what()));
  }
  const YAML::Node joints = root.IsMap() ? root["joints"] : YAML::Node();
  if (!joints || !joints.IsSequence()) {
    throw hardware::HardwareError("the model's controller configuration has no `joints` list");
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const YAML::Node j = joints[i];
    const std::string where = "the model's controller configuration, joints[" + std::to_string(i) + "]";
    if (!j.IsMap() || !j["name"] || !j["name"].IsScalar()) throw hardware::HardwareError(where + ": no name");
    const std::string name = j["name"].as<std::string>();
    int32_t id = -1;
    try {
      if (j["robot_id"]) id = j["robot_id"].as<int32_t>();
    } catch (const YAML::Exception&) {
      throw hardware::HardwareError(where + " '" + name + "': robot_id '" + YAML::Dump(j["robot_id"]) +
                                    "' is no integer");
    }
    if (id < 0) {
      throw hardware::HardwareError(where + " '" + name +
                                    "': no robot_id (the module tree the model was generated from gave none, "
                                    "so no drive board can be found for the joint)");
    }
    out.emplace_back(name, id);
  }
  return out;
}

std::vector<std::pair<std::string, int32_t>> model_binding(const std::string& config_yaml,
                                                           const std::vector<std::string>& modelled) {
  std::vector<std::pair<std::string, int32_t>> ids = joint_robot_ids(config_yaml);
  std::set<std::string> configured;
  for (const auto& [name, id] : ids) configured.insert(name);
  const std::set<std::string> model(modelled.begin(), modelled.end());
  for (const std::string& name : model) {
    if (!configured.count(name)) {
      throw hardware::HardwareError("joint '" + name + "' of the model is not in its controller configuration");
    }
  }
  for (const std::string& name : configured) {
    if (!model.count(name)) {
      throw hardware::HardwareError("joint '" + name + "' of the controller configuration is not in the model");
    }
  }
  return ids;
}

void EthercatHardware::step(double dt) {
  last_ = master_.cycle(image_);
  if (!last_.returned || last_.wkc != image_.expected_wkc) ++cycle_faults_;
  time_ += dt;
}

}  // namespace concert::ethercat
