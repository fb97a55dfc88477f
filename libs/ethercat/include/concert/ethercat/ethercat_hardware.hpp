#pragma once
// The robot's hardware on an EtherCAT ring (hardware::Hardware over the master): bring-up to OP,
// each joint bound to the drive board of its module's robot_id, one LRW per step(). What the
// robot service's `ethercat` backend stands on (services/robot/README.md).

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "concert/ethercat/drive_pdo.hpp"
#include "concert/ethercat/master.hpp"
#include "concert/ethercat/process_data.hpp"
#include "concert/hardware/hardware.hpp"

namespace concert::ethercat {

class EthercatHardware final : public hardware::Hardware {
 public:
  /// Scans the ring on `link`, maps the process data of every board `process_data` describes
  /// and brings the ring to OP with every drive disabled (holding). Throws MasterError naming
  /// the slave that refuses, ProcessDataError for a drive board type the codec cannot read.
  EthercatHardware(Link& link, ProcessDataCatalog process_data, MasterParams params = {});
  EthercatHardware(const EthercatHardware&) = delete;
  EthercatHardware& operator=(const EthercatHardware&) = delete;

  /// The ring as scanned (for concert/ethercat/scan).
  const ScanReport& scan() const { return report_; }

  /// Any thread: prepares the binding of joints to drive boards by robot_id (joint name,
  /// robot_id of its module), in the order given (the hardware order once switched);
  /// mounted() reports it from now on and the control thread's switch_prepared() runs it.
  /// Throws hardware::HardwareError naming the joint and the slave: no board with that robot_id,
  /// a board that is no drive (or whose process data is smaller than a drive's), two boards
  /// with the robot_id, two joints on one board, a joint listed twice. Nothing changes then. The binding prepared
  /// last again (a new version of the same robot's model) changes nothing either.
  void prepare_joints(const std::vector<std::pair<std::string, int32_t>>& joints);
  /// prepare_joints() and switch_prepared() at once (the control thread, or before it runs).
  void bind_joints(const std::vector<std::pair<std::string, int32_t>>& joints);

  /// Any thread: the binding prepared last (else the running one).
  [[nodiscard]] hardware::MountedHardware mounted() const override;
  /// Any thread, without locking: mounted().generation.
  [[nodiscard]] std::uint64_t mounted_generation() const override {
    return mounted_generation_.load(std::memory_order_acquire);
  }
  /// Control thread, at a cycle boundary: runs the binding prepared last; every drive of it
  /// starts disabled until its first command, and a board the new binding leaves out is
  /// disabled. Swaps buffers, allocates nothing.
  bool switch_prepared() override;

  [[nodiscard]] std::string backend() const override { return "ethercat"; }
  [[nodiscard]] const std::vector<std::string>& joint_names() const override { return names_; }
  [[nodiscard]] std::uint64_t generation() const override { return generation_; }
  /// The joints' last feedback; `time` counts the cycles' periods (DC time is still to come).
  void read(hardware::HardwareState& state) override;
  /// Commands for the next step(); every bound drive is enabled from its first command on.
  void write(const std::vector<hardware::DriveCommand>& commands) override;
  /// One cycle: outputs out, inputs in. A frame not back or a working counter short of the
  /// expected one is counted (cycle_faults()) and the last feedback kept.
  void step(double dt) override;

  /// Cycles that did not exchange every board's process data, since the start.
  uint64_t cycle_faults() const { return cycle_faults_; }
  const CycleResult& last_cycle() const { return last_; }
  /// What changed on the ring since the scan (after cycle faults).
  RingDiagnosis diagnose() { return master_.diagnose(report_); }

 private:
  struct Joint {
    std::string name;
    std::size_t slave = 0;  // index into image_.slaves
    DriveCodec codec;
  };
  struct Binding {
    std::vector<Joint> joints;
    std::vector<std::string> names;
    std::vector<bool> enabled;
    uint64_t generation = 0;
  };
  Master master_;
  ProcessDataCatalog process_data_;
  ScanReport report_;
  ProcessImage image_;
  std::vector<Joint> joints_;
  std::vector<std::string> names_;
  std::vector<bool> enabled_;
  uint64_t generation_ = 0;
  // The binding other threads prepared, not yet switched to; the one switched away from waits
  // in retired_ to be freed off the control thread (by the next prepare_joints()).
  mutable std::mutex binding_mutex_;
  std::optional<Binding> pending_;
  std::optional<Binding> retired_;
  uint64_t prepared_generation_ = 0;
  std::vector<std::pair<std::string, int32_t>> prepared_;  // what the binding prepared last was made from
  std::atomic<bool> has_pending_{false};
  std::atomic<uint64_t> mounted_generation_{0};
  uint64_t cycle_faults_ = 0;
  double time_ = 0;
  CycleResult last_;
};

/// The joints of a model's controller configuration (modelgen's controller.yaml: `joints`, each
/// with `name` and `robot_id`) with their modules' robot_ids, in file order: what
/// bind_joints() takes. Throws hardware::HardwareError naming the joint without a robot_id (a
/// model generated from a tree the scan gave no robot_ids) or the YAML's fault.
std::vector<std::pair<std::string, int32_t>> joint_robot_ids(const std::string& config_yaml);

/// What prepare_joints() takes for a model: joint_robot_ids(config_yaml), checked to name
/// exactly `modelled` (the model's moving joints, any order), since the robot refuses a model
/// whose joints are not the mounted ones. Throws hardware::HardwareError naming a joint one
/// side has and the other not.
std::vector<std::pair<std::string, int32_t>> model_binding(const std::string& config_yaml,
                                                           const std::vector<std::string>& modelled);

}  // namespace concert::ethercat
