#pragma once
// The robot's sensor data on DDS: a hardware::SensorSink that converts what the backend's
// sensor threads deliver (libs/sensors_dds) and writes it on the sensor topics
// (concert/sensors/...). Stream writers are best-effort keep-last 1: a write never waits for a
// reader. The mounted sensors go on the latched SensorList, with the robot's model version.

#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

#include "concert/dds/endpoint.hpp"
#include "concert/hardware/sensors.hpp"

namespace concert::robot::dds {

class SensorPublisher : public hardware::SensorSink {
 public:
  /// Creates the writers on `participant` (which must outlive this). `model_version` is what
  /// samples and the SensorList carry until set_model_version() changes it.
  explicit SensorPublisher(concert::dds::Participant& participant, uint32_t model_version = 0);

  /// Any thread: the robot's model version from now on. When it changes, the SensorList is
  /// published again at the new version (consumers resolve frames in that model).
  void set_model_version(uint32_t version);

  void on_sensors(const std::vector<hardware::SensorInfo>& mounted) override;
  /// Writes the colour image, the depth image and the camera info of the frame, in that order.
  void on_rgbd(const hardware::RgbdFrame& frame) override;
  void on_lidar(const hardware::LidarScan& scan) override;
  void on_scan2d(const hardware::LaserScan2d& scan) override;
  void on_sonars(const hardware::SonarRanges& ranges) override;
  void on_imu(const hardware::ImuSample& sample) override;

  /// Samples DDS refused or the conversion rejected (malformed frames), since creation; the
  /// first one is reported on stderr.
  uint64_t dropped() const { return dropped_.load(); }

 private:
  void publish_list();
  template <class F>
  void guarded(F&& f);

  std::atomic<uint32_t> model_version_;
  std::atomic<uint64_t> dropped_{0};
  concert::dds::Writer<msg::Image> rgb_;
  concert::dds::Writer<msg::Image> depth_;
  concert::dds::Writer<msg::CameraInfo> info_;
  concert::dds::Writer<msg::LidarScan> lidar_;
  concert::dds::Writer<msg::LaserScan> scan_;
  concert::dds::Writer<msg::SonarRanges> sonar_;
  concert::dds::Writer<msg::Imu> imu_;
  concert::dds::Writer<msg::SensorList> list_;

  std::mutex camera_mutex_;  ///< guards the image buffers, reused frame after frame
  msg::Image rgb_image_;
  msg::Image depth_image_;
  std::mutex list_mutex_;
  std::vector<hardware::SensorInfo> mounted_;
  bool have_list_ = false;
};

}  // namespace concert::robot::dds
