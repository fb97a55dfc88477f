#include "concert/ethercat/drive_pdo.hpp"

#include <cstring>
#include <string>

namespace concert::ethercat {
namespace {

std::size_t find(const std::vector<PdoEntry>& entries, const BoardProcessData& board, const char* name,
                 EntryType type, const char* side) {
  for (const PdoEntry& e : entries) {
    if (e.name != name) continue;
    if (e.type != type) {
      throw ProcessDataError("board '" + board.name + "' (ESC type " + std::to_string(board.esc_type) +
                             "): " + side + " entry '" + name + "' is " + to_string(e.type) +
                             ", a drive needs " + to_string(type));
    }
    return e.offset;
  }
  throw ProcessDataError("board '" + board.name + "' (ESC type " + std::to_string(board.esc_type) +
                         ") has no " + side + " entry '" + name + "' a drive needs");
}

void put_f(std::span<uint8_t> b, std::size_t at, double v) {
  const auto f = static_cast<float>(v);
  std::memcpy(b.data() + at, &f, sizeof f);
}
double get_f(std::span<const uint8_t> b, std::size_t at) {
  float f;
  std::memcpy(&f, b.data() + at, sizeof f);
  return f;
}
void put_u16(std::span<uint8_t> b, std::size_t at, uint16_t v) {
  b[at] = static_cast<uint8_t>(v & 0xFF);
  b[at + 1] = static_cast<uint8_t>(v >> 8);
}
uint16_t get_u16(std::span<const uint8_t> b, std::size_t at) {
  return static_cast<uint16_t>(b[at] | (b[at + 1] << 8));
}

// The mode byte of the outputs (process_data.yaml): 0 off, 1 position, 2 velocity, 3 effort,
// 4 impedance.
uint8_t mode_byte(hardware::DriveMode mode) {
  switch (mode) {
    case hardware::DriveMode::kPosition: return 1;
    case hardware::DriveMode::kVelocity: return 2;
    case hardware::DriveMode::kEffort: return 3;
    case hardware::DriveMode::kImpedance: return 4;
  }
  return 0;
}

}  // namespace

DriveCodec::DriveCodec(const BoardProcessData& board)
    : output_bytes_(board.output_bytes()), input_bytes_(board.input_bytes()) {
  const auto o = [&](const char* n, EntryType t) { return find(board.outputs, board, n, t, "output"); };
  const auto i = [&](const char* n, EntryType t) { return find(board.inputs, board, n, t, "input"); };
  using T = EntryType;
  out_ = {o("control_word", T::kUint16), o("mode", T::kInt8),       o("position_ref", T::kFloat32),
          o("velocity_ref", T::kFloat32), o("torque_ff", T::kFloat32), o("kp", T::kFloat32),
          o("kd", T::kFloat32),           o("max_torque", T::kFloat32)};
  in_ = {i("status_word", T::kUint16),     i("fault", T::kUint16),
         i("link_position", T::kFloat32),  i("motor_position", T::kFloat32),
         i("velocity", T::kFloat32),       i("torque", T::kFloat32),
         i("motor_temperature", T::kFloat32), i("board_temperature", T::kFloat32)};
}

void DriveCodec::encode(const hardware::DriveCommand& c, bool enable, std::span<uint8_t> b) const {
  put_u16(b, out_.control_word, enable ? kControlEnableOperation : 0);
  b[out_.mode] = enable ? mode_byte(c.mode) : 0;
  put_f(b, out_.position_ref, c.position);
  put_f(b, out_.velocity_ref, c.velocity);
  put_f(b, out_.torque_ff, c.effort);
  put_f(b, out_.kp, c.stiffness);
  put_f(b, out_.kd, c.damping);
  put_f(b, out_.max_torque, c.max_effort);
}

hardware::DriveCommand DriveCodec::decode_command(std::span<const uint8_t> b, bool& enabled) const {
  hardware::DriveCommand c;
  const uint8_t mode = b[out_.mode];
  enabled = (get_u16(b, out_.control_word) & kControlEnableOperation) == kControlEnableOperation &&
            mode >= 1 && mode <= 4;
  switch (mode) {
    case 2: c.mode = hardware::DriveMode::kVelocity; break;
    case 3: c.mode = hardware::DriveMode::kEffort; break;
    case 4: c.mode = hardware::DriveMode::kImpedance; break;
    default: c.mode = hardware::DriveMode::kPosition; break;
  }
  c.position = get_f(b, out_.position_ref);
  c.velocity = get_f(b, out_.velocity_ref);
  c.effort = get_f(b, out_.torque_ff);
  c.stiffness = get_f(b, out_.kp);
  c.damping = get_f(b, out_.kd);
  c.max_effort = get_f(b, out_.max_torque);
  return c;
}

void DriveCodec::encode(const DriveFeedback& f, std::span<uint8_t> b) const {
  put_u16(b, in_.status_word, f.status_word);
  put_u16(b, in_.fault, f.fault);
  put_f(b, in_.link_position, f.link_position);
  put_f(b, in_.motor_position, f.motor_position);
  put_f(b, in_.velocity, f.velocity);
  put_f(b, in_.torque, f.torque);
  put_f(b, in_.motor_temperature, f.motor_temperature);
  put_f(b, in_.board_temperature, f.board_temperature);
}

DriveFeedback DriveCodec::decode_feedback(std::span<const uint8_t> b) const {
  DriveFeedback f;
  f.status_word = get_u16(b, in_.status_word);
  f.fault = get_u16(b, in_.fault);
  f.link_position = get_f(b, in_.link_position);
  f.motor_position = get_f(b, in_.motor_position);
  f.velocity = get_f(b, in_.velocity);
  f.torque = get_f(b, in_.torque);
  f.motor_temperature = get_f(b, in_.motor_temperature);
  f.board_temperature = get_f(b, in_.board_temperature);
  return f;
}

}  // namespace concert::ethercat
