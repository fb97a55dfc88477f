#include "sensor_publisher.hpp"

#include <exception>
#include <iostream>

#include "concert/common/clock.hpp"
#include "concert/sensors_dds/conversions.hpp"

namespace concert::robot::dds {

namespace topics = concert::dds::topics;
namespace convert = concert::sensors_dds;

SensorPublisher::SensorPublisher(concert::dds::Participant& participant, uint32_t model_version)
    : model_version_(model_version),
      rgb_(participant, topics::camera_rgb),
      depth_(participant, topics::camera_depth),
      info_(participant, topics::camera_info),
      lidar_(participant, topics::lidar),
      scan_(participant, topics::scan),
      sonar_(participant, topics::sonar),
      imu_(participant, topics::imu),
      list_(participant, topics::sensor_list) {}

/// Runs f on a sensor thread: a malformed sample or a refused write is counted (the first one
/// reported on stderr), never thrown into the backend.
template <class F>
void SensorPublisher::guarded(F&& f) {
  try {
    if (!f()) dropped_.fetch_add(1);
  } catch (const std::exception& e) {
    if (dropped_.fetch_add(1) == 0)
      std::cerr << "concert_robot: sensor sample dropped: " << e.what() << "\n";
  }
}

void SensorPublisher::set_model_version(uint32_t version) {
  if (model_version_.exchange(version) != version) publish_list();
}

void SensorPublisher::on_sensors(const std::vector<hardware::SensorInfo>& mounted) {
  {
    std::lock_guard lock(list_mutex_);
    mounted_ = mounted;
    have_list_ = true;
  }
  publish_list();
}

void SensorPublisher::publish_list() {
  std::lock_guard lock(list_mutex_);
  if (!have_list_) return;
  guarded([&] { return list_.write(convert::to_msg(mounted_, model_version_.load(), now_ns())); });
}

void SensorPublisher::on_rgbd(const hardware::RgbdFrame& frame) {
  const uint32_t version = model_version_.load();
  std::lock_guard lock(camera_mutex_);
  guarded([&] {
    convert::to_rgb_image(frame, version, rgb_image_);
    return rgb_.write(rgb_image_);
  });
  guarded([&] {
    convert::to_depth_image(frame, version, depth_image_);
    return depth_.write(depth_image_);
  });
  guarded([&] { return info_.write(convert::to_camera_info(frame, version)); });
}

void SensorPublisher::on_lidar(const hardware::LidarScan& scan) {
  guarded([&] { return lidar_.write(convert::to_msg(scan, model_version_.load())); });
}

void SensorPublisher::on_scan2d(const hardware::LaserScan2d& scan) {
  guarded([&] { return scan_.write(convert::to_msg(scan, model_version_.load())); });
}

void SensorPublisher::on_sonars(const hardware::SonarRanges& ranges) {
  guarded([&] { return sonar_.write(convert::to_msg(ranges, model_version_.load())); });
}

void SensorPublisher::on_imu(const hardware::ImuSample& sample) {
  guarded([&] { return imu_.write(convert::to_msg(sample, model_version_.load())); });
}

}  // namespace concert::robot::dds
