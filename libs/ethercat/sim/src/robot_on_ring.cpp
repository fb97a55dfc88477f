#include "concert/ethercat/robot_on_ring.hpp"

#include <filesystem>
#include <optional>

#include "concert/sim/sim_hardware.hpp"
#include "concert/world/world.hpp"

namespace concert::ethercat {

RobotOnRing::RobotOnRing(hardware::Hardware& hardware, const sim::SimulatedRobot& robot,
                         const BoardProcessData& drive_board, RobotOnRingParams params)
    : hardware_(hardware), codec_(drive_board), drive_type_(drive_board.esc_type), params_(params) {
  const auto& joints = hardware_.joint_names();
  for (const std::string& joint : joints) {
    const auto it = robot.joint_robot_ids.find(joint);
    if (it == robot.joint_robot_ids.end() || it->second < 0) {
      throw std::runtime_error("joint '" + joint + "' of " + robot.source +
                               " belongs to a module without a robot_id: no drive board on the "
                               "ring can be told to be its");
    }
    robot_ids_.push_back(it->second);
  }
  commands_.resize(joints.size());
  holding_.assign(joints.size(), true);
  hold_at_.assign(joints.size(), 0.0);
  board_of_.assign(joints.size(), -1);
  hardware_.read(state_);
  for (std::size_t j = 0; j < joints.size(); ++j) hold_at_[j] = state_.position[j];
}

void RobotOnRing::exchange(std::span<BoardIo> boards, uint64_t) {
  const auto& joints = hardware_.joint_names();
  unmatched_.clear();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    board_of_[j] = -1;
    for (std::size_t b = 0; b < boards.size(); ++b) {
      if (boards[b].esc->robot_id == robot_ids_[j] && boards[b].board->esc_type == drive_type_) {
        board_of_[j] = static_cast<int>(b);
        break;
      }
    }
    bool run = false;
    if (board_of_[j] >= 0 && boards[static_cast<std::size_t>(board_of_[j])].state == esc::AlState::kOp) {
      commands_[j] = codec_.decode_command(boards[static_cast<std::size_t>(board_of_[j])].outputs, run);
    }
    if (board_of_[j] < 0) unmatched_.push_back(joints[j]);
    if (!run) {
      // Not told to run: hold where the joint was when it stopped running (a closed brake).
      if (!holding_[j]) hold_at_[j] = state_.position[j];
      commands_[j] = hardware::DriveCommand{};
      commands_[j].mode = hardware::DriveMode::kPosition;
      commands_[j].position = hold_at_[j];
    }
    holding_[j] = !run;
  }
  hardware_.write(commands_);
  hardware_.step(params_.period);
  hardware_.read(state_);
  ++steps_;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (board_of_[j] < 0) continue;
    BoardIo& io = boards[static_cast<std::size_t>(board_of_[j])];
    DriveFeedback f;
    f.status_word = holding_[j] ? 0 : kStatusOperationEnabled;
    f.link_position = state_.position[j];
    f.motor_position = state_.position[j];
    f.velocity = state_.velocity[j];
    f.torque = state_.effort[j];
    f.motor_temperature = params_.temperature;
    f.board_temperature = params_.temperature;
    codec_.encode(f, io.inputs);
  }
}

struct RobotBehindRing::Impl {
  VirtualRing* ring = nullptr;
  std::optional<sim::SimHardware> hardware;
  std::optional<RobotOnRing> robot;
};

RobotBehindRing::RobotBehindRing(VirtualRing& ring, const std::vector<std::string>& module_dbs,
                                 const std::string& assembly_file, const std::string& world_file,
                                 const ProcessDataCatalog& process_data)
    : impl_(std::make_unique<Impl>()) {
  const sim::AssemblyBuilder builder(std::vector<std::filesystem::path>(module_dbs.begin(), module_dbs.end()));
  const sim::SimulatedRobot mounted = builder.build(assembly_file);
  const BoardProcessData* drive = process_data.find(21);
  if (!drive) throw std::runtime_error("the process data has no drive board (ESC type 21) to put the robot behind");
  sim::SimParams params;
  params.sensors.enabled = false;  // the ring carries the drives only
  const world::World world = world_file.empty() ? world::World{} : world::load_world_file(world_file);
  impl_->hardware.emplace(mounted, world, params);
  impl_->robot.emplace(*impl_->hardware, mounted, *drive);
  RobotOnRing* robot = &*impl_->robot;
  impl_->ring = &ring;
  ring.set_application([robot](std::span<BoardIo> boards, uint64_t now) { robot->exchange(boards, now); });
}

RobotBehindRing::~RobotBehindRing() {
  // The ring may outlive the robot: it must not call into it then.
  if (impl_ && impl_->ring) impl_->ring->set_application({});
}
std::size_t RobotBehindRing::joints() const { return impl_->hardware->joint_names().size(); }
const RobotOnRing& RobotBehindRing::robot() const { return *impl_->robot; }

}  // namespace concert::ethercat
