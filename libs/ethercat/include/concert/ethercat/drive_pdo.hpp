#pragma once
// The drive board's process data (data/module_db/process_data.yaml, ESC type 21) as the robot's
// types: a DriveCommand into the board's outputs and back (the master writes them, the virtual
// board reads them), the board's feedback into its inputs and back. Entries are found by name
// once, so the cyclic path only copies bytes.

#include <cstdint>
#include <span>

#include "concert/ethercat/process_data.hpp"
#include "concert/hardware/hardware.hpp"

namespace concert::ethercat {

/// CiA 402 control word "enable operation" (switch on, enable voltage, quick stop off, enable
/// operation) and the status word of a drive in "operation enabled".
inline constexpr uint16_t kControlEnableOperation = 0x000F;
inline constexpr uint16_t kStatusOperationEnabled = 0x0027;

/// What a drive board reports every cycle.
struct DriveFeedback {
  uint16_t status_word = 0;
  uint16_t fault = 0;                ///< 0: none
  double link_position = 0;          ///< [rad]
  double motor_position = 0;         ///< [rad], motor side through the gear
  double velocity = 0;               ///< [rad/s]
  double torque = 0;                 ///< [N m], measured
  double motor_temperature = 0;      ///< [deg C]
  double board_temperature = 0;      ///< [deg C]
};

class DriveCodec {
 public:
  /// Throws ProcessDataError naming the entry `board` lacks (or has with another type).
  explicit DriveCodec(const BoardProcessData& board);

  std::size_t output_bytes() const { return output_bytes_; }
  std::size_t input_bytes() const { return input_bytes_; }

  /// The command into the outputs; `enable` false sends mode 0 (off) with the control word
  /// cleared, as a master does for a drive it holds disabled.
  void encode(const hardware::DriveCommand& command, bool enable, std::span<uint8_t> outputs) const;
  /// The command the outputs carry; `enabled` set to whether the drive is told to run.
  hardware::DriveCommand decode_command(std::span<const uint8_t> outputs, bool& enabled) const;

  void encode(const DriveFeedback& feedback, std::span<uint8_t> inputs) const;
  DriveFeedback decode_feedback(std::span<const uint8_t> inputs) const;

 private:
  struct Out {
    std::size_t control_word, mode, position_ref, velocity_ref, torque_ff, kp, kd, max_torque;
  } out_{};
  struct In {
    std::size_t status_word, fault, link_position, motor_position, velocity, torque,
        motor_temperature, board_temperature;
  } in_{};
  std::size_t output_bytes_ = 0;
  std::size_t input_bytes_ = 0;
};

}  // namespace concert::ethercat
