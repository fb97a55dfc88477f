#pragma once
// Sensor data between libs/hardware's plain C++ types (sensors.hpp) and the IDL types of the
// sensor topics (idl/sensors.idl). Writers (the robot service) and readers (the concert tool,
// services) both convert here, so the two sides cannot drift apart.
//
// Stamps: hardware stamps are seconds (double), IDL stamps nanoseconds (rounded). Instances are
// keyed by concert::dds::sensor_id(sensor name). Depth travels as "16UC1", little-endian.

#include <cstdint>
#include <string_view>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "sensors.h"

namespace concert::sensors_dds {

/// Image encodings of the camera topics.
inline constexpr std::string_view kRgb8 = "rgb8";
inline constexpr std::string_view kDepth16 = "16UC1";

/// [s] -> [ns], rounded to the nearest nanosecond.
int64_t to_stamp_ns(double seconds);
/// [ns] -> [s].
double from_stamp_ns(int64_t ns);

/// The colour image of `frame` ("rgb8") into `out`, reusing its buffer (no allocation once it
/// has grown to the image size). Throws std::invalid_argument naming the camera when
/// frame.rgb is not width * height * 3 bytes.
void to_rgb_image(const hardware::RgbdFrame& frame, uint32_t model_version, msg::Image& out);
/// The depth image of `frame` ("16UC1", depth_scale of the frame) into `out`, reusing its
/// buffer. Throws std::invalid_argument naming the camera when frame.depth is not
/// width * height values.
void to_depth_image(const hardware::RgbdFrame& frame, uint32_t model_version, msg::Image& out);
/// The camera model of `frame`: intrinsics, distortion "none", depth scale and range.
msg::CameraInfo to_camera_info(const hardware::RgbdFrame& frame, uint32_t model_version);

/// Checks that `image` is a well-formed image of `encoding` ("rgb8" or "16UC1"): size,
/// step and data length agree. Throws std::invalid_argument naming the sensor and the fault.
void check_image(const msg::Image& image, std::string_view encoding);

/// One RGB-D frame from its colour image, depth image and camera info (same camera, same
/// stamp, same size). Throws std::invalid_argument naming what does not match.
hardware::RgbdFrame to_rgbd_frame(const msg::Image& rgb, const msg::Image& depth,
                                  const msg::CameraInfo& info);
/// One depth frame (rgb left empty) from a depth image and its camera info (same camera, same
/// size), for readers that need no colour. Throws std::invalid_argument naming the camera and
/// what does not match (encoding, size, step, another camera's info).
hardware::RgbdFrame to_depth_frame(const msg::Image& depth, const msg::CameraInfo& info);

msg::LidarScan to_msg(const hardware::LidarScan& scan, uint32_t model_version);
/// Throws std::invalid_argument naming the lidar when ranges is not rings * columns long.
hardware::LidarScan from_msg(const msg::LidarScan& scan);

msg::LaserScan to_msg(const hardware::LaserScan2d& scan, uint32_t model_version);
hardware::LaserScan2d from_msg(const msg::LaserScan& scan);

msg::SonarRanges to_msg(const hardware::SonarRanges& ranges, uint32_t model_version);
hardware::SonarRanges from_msg(const msg::SonarRanges& ranges);

msg::Imu to_msg(const hardware::ImuSample& sample, uint32_t model_version);
hardware::ImuSample from_msg(const msg::Imu& sample);

/// The mounted sensors at `model_version`, stamped `stamp_ns` [ns since the Unix epoch].
msg::SensorList to_msg(const std::vector<hardware::SensorInfo>& sensors, uint32_t model_version,
                       int64_t stamp_ns);
std::vector<hardware::SensorInfo> from_msg(const msg::SensorList& list);

}  // namespace concert::sensors_dds
