#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/hardware/sensors.hpp"

namespace concert::hardware {

/// Any hardware-level failure (backend could not be built, wrong command vector size...).
class HardwareError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How a joint drive interprets its reference (as the CONCERT drives do on their own
/// inner loop): tau = kp (q_ref - q) + kd (qd_ref - qd) + tau_ff, saturated at the effort limit.
enum class DriveMode : std::uint8_t {
  kPosition,   ///< drive's own stiff position gains, q_ref (and qd_ref as feed-forward)
  kVelocity,   ///< drive's own velocity gain, qd_ref
  kEffort,     ///< tau_ff only
  kImpedance,  ///< caller's kp, kd, q_ref, qd_ref, tau_ff
};

/// Reference for one joint drive, in the hardware's joint order.
struct DriveCommand {
  DriveMode mode{DriveMode::kPosition};
  double position{0.0};   ///< [rad] or [m]
  double velocity{0.0};   ///< [rad/s] or [m/s]
  double effort{0.0};     ///< feed-forward [Nm] or [N]
  double stiffness{0.0};  ///< [Nm/rad] (impedance mode)
  double damping{0.0};    ///< [Nm s/rad] (impedance mode)
  /// Torque limit for this cycle [Nm] or [N] (a drive's max-torque object, CiA 402 0x6072),
  /// below its rated peak; 0: the rated peak. The robot core folds it back as a drive heats.
  double max_effort{0.0};
};

/// What the drives report, in the hardware's joint order.
struct HardwareState {
  double time{0.0};               ///< hardware clock [s] (simulated time for the sim backend)
  std::vector<double> position;   ///< [rad] or [m]
  std::vector<double> velocity;   ///< [rad/s] or [m/s]
  std::vector<double> effort;     ///< measured joint torque [Nm] or force [N]
};

/// What is mounted: the hardware generation and its joints (hardware order).
struct MountedHardware {
  std::uint64_t generation{0};
  std::vector<std::string> joint_names;
};

/// The hardware abstraction: the only thing the robot core talks to. Implemented by the
/// MuJoCo simulation (`sim`, default) and, on the real robot, an EtherCAT master
/// (`ethercat`, see services/robot/README.md for what it must provide).
///
/// Cycle contract (1 kHz): switch_prepared() -> read() -> compute -> write() -> step(). One
/// control thread owns the hardware; only mounted() and the preparing calls a backend
/// documents as such may come from other threads.
class Hardware {
 public:
  virtual ~Hardware() = default;
  /// Backend name ("sim", "ethercat").
  [[nodiscard]] virtual std::string backend() const = 0;
  /// Names of the mounted actuated joints, in hardware order.
  [[nodiscard]] virtual const std::vector<std::string>& joint_names() const = 0;
  /// Increases whenever the mounted hardware changes (hot swap); joint_names() may then differ.
  [[nodiscard]] virtual std::uint64_t generation() const = 0;
  /// Any thread: the hardware the control thread runs once it has switched to what was
  /// prepared (see switch_prepared()). The default (hardware that never changes) is the
  /// running hardware.
  [[nodiscard]] virtual MountedHardware mounted() const { return {generation(), joint_names()}; }
  /// Any thread: mounted().generation without copying the joint names.
  [[nodiscard]] virtual std::uint64_t mounted_generation() const { return mounted().generation; }
  /// Control thread, at a cycle boundary: switches to hardware (or a world) another thread
  /// prepared, without allocating; true if it switched. The default has nothing to switch.
  virtual bool switch_prepared() { return false; }
  /// Latest measurements; resizes `state` to the joint count.
  virtual void read(HardwareState& state) = 0;
  /// New references, one per joint (throws HardwareError on a size mismatch).
  virtual void write(const std::vector<DriveCommand>& commands) = 0;
  /// Advance one control period `dt` [s]: the sim integrates physics, a real master
  /// exchanges process data with the drives.
  virtual void step(double dt) = 0;

  /// Any thread: where the backend's sensors deliver their data from now on (nullptr:
  /// nowhere; the sink must outlive the backend or be replaced first). Backends without
  /// sensors ignore it.
  virtual void set_sensor_sink(SensorSink* sink) { (void)sink; }
  /// Any thread: the sensors mounted now (empty for backends without sensors).
  [[nodiscard]] virtual std::vector<SensorInfo> sensors() const { return {}; }
};

}  // namespace concert::hardware
