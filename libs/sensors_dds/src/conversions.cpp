#include "concert/sensors_dds/conversions.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "concert/dds/catalogue.hpp"

namespace concert::sensors_dds {
namespace {

static_assert(std::endian::native == std::endian::little,
              "16UC1 depth is little-endian on the wire; this host would need a byte swap");

std::string camera(std::string_view sensor) { return "camera '" + std::string(sensor) + "'"; }

/// Header fields every camera image shares.
void image_header(const hardware::RgbdFrame& frame, uint32_t model_version,
                  std::string_view encoding, uint32_t bytes_per_pixel, msg::Image& out) {
  out.sensor_id(dds::sensor_id(frame.sensor));
  out.model_version(model_version);
  out.stamp_ns(to_stamp_ns(frame.stamp));
  out.sensor(frame.sensor);
  out.frame(frame.frame);
  out.encoding(std::string(encoding));
  out.width(frame.intrinsics.width);
  out.height(frame.intrinsics.height);
  out.step(frame.intrinsics.width * bytes_per_pixel);
}

size_t pixels(const hardware::RgbdFrame& frame) {
  return static_cast<size_t>(frame.intrinsics.width) * frame.intrinsics.height;
}

msg::Vector3 to_vector(const Eigen::Vector3d& v) {
  msg::Vector3 out;
  out.x(v.x());
  out.y(v.y());
  out.z(v.z());
  return out;
}

Eigen::Vector3d from_vector(const msg::Vector3& v) { return {v.x(), v.y(), v.z()}; }

hardware::SensorType from_kind(msg::SensorKind kind, std::string_view sensor) {
  switch (kind) {
    case msg::SENSOR_RGBD:
      return hardware::SensorType::kRgbd;
    case msg::SENSOR_LIDAR:
      return hardware::SensorType::kLidar;
    case msg::SENSOR_SONAR:
      return hardware::SensorType::kSonar;
    case msg::SENSOR_IMU:
      return hardware::SensorType::kImu;
  }
  throw std::invalid_argument("SensorList: sensor '" + std::string(sensor) +
                              "' has an unknown kind " + std::to_string(static_cast<int>(kind)));
}

msg::SensorKind to_kind(hardware::SensorType type) {
  switch (type) {
    case hardware::SensorType::kRgbd:
      return msg::SENSOR_RGBD;
    case hardware::SensorType::kLidar:
      return msg::SENSOR_LIDAR;
    case hardware::SensorType::kSonar:
      return msg::SENSOR_SONAR;
    case hardware::SensorType::kImu:
      return msg::SENSOR_IMU;
  }
  throw std::logic_error("unknown hardware::SensorType");
}

}  // namespace

int64_t to_stamp_ns(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e9)); }

double from_stamp_ns(int64_t ns) { return static_cast<double>(ns) * 1e-9; }

void to_rgb_image(const hardware::RgbdFrame& frame, uint32_t model_version, msg::Image& out) {
  if (frame.rgb.size() != pixels(frame) * 3) {
    throw std::invalid_argument(
        camera(frame.sensor) + ": colour image has " + std::to_string(frame.rgb.size()) +
        " bytes, not width * height * 3 = " + std::to_string(pixels(frame) * 3));
  }
  image_header(frame, model_version, kRgb8, 3, out);
  out.depth_scale(0.0);
  out.data().assign(frame.rgb.begin(), frame.rgb.end());
}

void to_depth_image(const hardware::RgbdFrame& frame, uint32_t model_version, msg::Image& out) {
  if (frame.depth.size() != pixels(frame)) {
    throw std::invalid_argument(camera(frame.sensor) + ": depth image has " +
                                std::to_string(frame.depth.size()) +
                                " values, not width * height = " + std::to_string(pixels(frame)));
  }
  image_header(frame, model_version, kDepth16, 2, out);
  out.depth_scale(frame.depth_scale);
  auto& data = out.data();
  data.resize(frame.depth.size() * sizeof(uint16_t));
  if (!data.empty()) std::memcpy(data.data(), frame.depth.data(), data.size());
}

msg::CameraInfo to_camera_info(const hardware::RgbdFrame& frame, uint32_t model_version) {
  msg::CameraInfo out;
  out.sensor_id(dds::sensor_id(frame.sensor));
  out.model_version(model_version);
  out.stamp_ns(to_stamp_ns(frame.stamp));
  out.sensor(frame.sensor);
  out.frame(frame.frame);
  out.width(frame.intrinsics.width);
  out.height(frame.intrinsics.height);
  out.fx(frame.intrinsics.fx);
  out.fy(frame.intrinsics.fy);
  out.cx(frame.intrinsics.cx);
  out.cy(frame.intrinsics.cy);
  out.distortion_model("none");
  out.depth_scale(frame.depth_scale);
  out.depth_min(frame.depth_min);
  out.depth_max(frame.depth_max);
  return out;
}

void check_image(const msg::Image& image, std::string_view encoding) {
  const std::string who = camera(image.sensor());
  if (image.encoding() != encoding) {
    throw std::invalid_argument(who + ": image encoding is '" + image.encoding() + "', expected '" +
                                std::string(encoding) + "'");
  }
  const uint32_t bytes_per_pixel = encoding == kRgb8 ? 3 : 2;
  if (image.step() < image.width() * bytes_per_pixel) {
    throw std::invalid_argument(who + ": " + std::string(encoding) + " image step " +
                                std::to_string(image.step()) + " is shorter than a row of " +
                                std::to_string(image.width()) + " px");
  }
  const size_t expected = static_cast<size_t>(image.step()) * image.height();
  if (image.data().size() != expected) {
    throw std::invalid_argument(who + ": " + std::string(encoding) + " image has " +
                                std::to_string(image.data().size()) +
                                " bytes, not step * height = " + std::to_string(expected));
  }
}

hardware::RgbdFrame to_depth_frame(const msg::Image& depth, const msg::CameraInfo& info) {
  check_image(depth, kDepth16);
  const std::string who = camera(depth.sensor());
  if (info.sensor() != depth.sensor()) {
    throw std::invalid_argument(who + ": camera info of '" + info.sensor() + "' is not the same camera's");
  }
  if (info.width() != depth.width() || info.height() != depth.height()) {
    throw std::invalid_argument(who + ": sizes differ: depth " + std::to_string(depth.width()) + "x" +
                                std::to_string(depth.height()) + ", camera info " +
                                std::to_string(info.width()) + "x" + std::to_string(info.height()));
  }
  hardware::RgbdFrame frame;
  frame.sensor = depth.sensor();
  frame.frame = depth.frame();
  frame.stamp = from_stamp_ns(depth.stamp_ns());
  frame.intrinsics = {depth.width(), depth.height(), info.fx(), info.fy(), info.cx(), info.cy()};
  const size_t depth_row = static_cast<size_t>(depth.width()) * 2;
  frame.depth.resize(static_cast<size_t>(depth.width()) * depth.height());
  for (size_t v = 0; v < depth.height(); ++v) {
    std::memcpy(reinterpret_cast<uint8_t*>(frame.depth.data()) + v * depth_row,
                depth.data().data() + v * depth.step(), depth_row);
  }
  frame.depth_scale = depth.depth_scale();
  frame.depth_min = info.depth_min();
  frame.depth_max = info.depth_max();
  return frame;
}

hardware::RgbdFrame to_rgbd_frame(const msg::Image& rgb, const msg::Image& depth,
                                  const msg::CameraInfo& info) {
  check_image(rgb, kRgb8);
  check_image(depth, kDepth16);
  const std::string who = camera(rgb.sensor());
  if (depth.sensor() != rgb.sensor() || info.sensor() != rgb.sensor()) {
    throw std::invalid_argument(who + ": depth image of '" + depth.sensor() +
                                "' and camera info of '" + info.sensor() +
                                "' are not the same camera's");
  }
  if (depth.stamp_ns() != rgb.stamp_ns()) {
    throw std::invalid_argument(who + ": colour stamp " + std::to_string(rgb.stamp_ns()) +
                                " ns and depth stamp " + std::to_string(depth.stamp_ns()) +
                                " ns differ");
  }
  if (depth.width() != rgb.width() || depth.height() != rgb.height() ||
      info.width() != rgb.width() || info.height() != rgb.height()) {
    throw std::invalid_argument(who + ": sizes differ: colour " + std::to_string(rgb.width()) +
                                "x" + std::to_string(rgb.height()) + ", depth " +
                                std::to_string(depth.width()) + "x" +
                                std::to_string(depth.height()) + ", camera info " +
                                std::to_string(info.width()) + "x" + std::to_string(info.height()));
  }
  hardware::RgbdFrame frame = to_depth_frame(depth, info);
  frame.frame = rgb.frame();
  frame.stamp = from_stamp_ns(rgb.stamp_ns());
  const size_t row = static_cast<size_t>(rgb.width()) * 3;
  frame.rgb.resize(row * rgb.height());
  for (size_t v = 0; v < rgb.height(); ++v) {
    std::memcpy(frame.rgb.data() + v * row, rgb.data().data() + v * rgb.step(), row);
  }
  return frame;
}

msg::LidarScan to_msg(const hardware::LidarScan& scan, uint32_t model_version) {
  msg::LidarScan out;
  out.sensor_id(dds::sensor_id(scan.sensor));
  out.model_version(model_version);
  out.stamp_ns(to_stamp_ns(scan.stamp));
  out.sensor(scan.sensor);
  out.frame(scan.frame);
  out.elevations(scan.elevations);
  out.azimuth_min(scan.azimuth_min);
  out.azimuth_increment(scan.azimuth_increment);
  out.columns(scan.columns);
  out.range_min(scan.range_min);
  out.range_max(scan.range_max);
  out.ranges(scan.ranges);
  return out;
}

hardware::LidarScan from_msg(const msg::LidarScan& scan) {
  const size_t expected = scan.elevations().size() * scan.columns();
  if (scan.ranges().size() != expected) {
    throw std::invalid_argument(
        "lidar '" + scan.sensor() + "': " + std::to_string(scan.ranges().size()) +
        " ranges, not rings * columns = " + std::to_string(scan.elevations().size()) + " * " +
        std::to_string(scan.columns()));
  }
  hardware::LidarScan out;
  out.sensor = scan.sensor();
  out.frame = scan.frame();
  out.stamp = from_stamp_ns(scan.stamp_ns());
  out.elevations = scan.elevations();
  out.azimuth_min = scan.azimuth_min();
  out.azimuth_increment = scan.azimuth_increment();
  out.columns = scan.columns();
  out.ranges = scan.ranges();
  out.range_min = scan.range_min();
  out.range_max = scan.range_max();
  return out;
}

msg::LaserScan to_msg(const hardware::LaserScan2d& scan, uint32_t model_version) {
  msg::LaserScan out;
  out.model_version(model_version);
  out.stamp_ns(to_stamp_ns(scan.stamp));
  out.frame(scan.frame);
  out.angle_min(scan.angle_min);
  out.angle_increment(scan.angle_increment);
  out.range_min(scan.range_min);
  out.range_max(scan.range_max);
  out.ranges(scan.ranges);
  return out;
}

hardware::LaserScan2d from_msg(const msg::LaserScan& scan) {
  hardware::LaserScan2d out;
  out.frame = scan.frame();
  out.stamp = from_stamp_ns(scan.stamp_ns());
  out.angle_min = scan.angle_min();
  out.angle_increment = scan.angle_increment();
  out.ranges = scan.ranges();
  out.range_min = scan.range_min();
  out.range_max = scan.range_max();
  return out;
}

msg::SonarRanges to_msg(const hardware::SonarRanges& ranges, uint32_t model_version) {
  msg::SonarRanges out;
  out.model_version(model_version);
  out.stamp_ns(to_stamp_ns(ranges.stamp));
  for (const auto& s : ranges.sonars) {
    msg::SonarRange r;
    r.sensor(s.sensor);
    r.frame(s.frame);
    r.range(s.range);
    r.range_min(s.range_min);
    r.range_max(s.range_max);
    r.field_of_view(s.field_of_view);
    out.sonars().push_back(std::move(r));
  }
  return out;
}

hardware::SonarRanges from_msg(const msg::SonarRanges& ranges) {
  hardware::SonarRanges out;
  out.stamp = from_stamp_ns(ranges.stamp_ns());
  for (const auto& r : ranges.sonars()) {
    out.sonars.push_back(
        {r.sensor(), r.frame(), r.range(), r.range_min(), r.range_max(), r.field_of_view()});
  }
  return out;
}

msg::Imu to_msg(const hardware::ImuSample& sample, uint32_t model_version) {
  msg::Imu out;
  out.sensor_id(dds::sensor_id(sample.sensor));
  out.model_version(model_version);
  out.stamp_ns(to_stamp_ns(sample.stamp));
  out.sensor(sample.sensor);
  out.frame(sample.frame);
  out.angular_velocity(to_vector(sample.angular_velocity));
  out.linear_acceleration(to_vector(sample.linear_acceleration));
  out.angular_velocity_variance(sample.angular_velocity_variance);
  out.linear_acceleration_variance(sample.linear_acceleration_variance);
  return out;
}

hardware::ImuSample from_msg(const msg::Imu& sample) {
  hardware::ImuSample out;
  out.sensor = sample.sensor();
  out.frame = sample.frame();
  out.stamp = from_stamp_ns(sample.stamp_ns());
  out.angular_velocity = from_vector(sample.angular_velocity());
  out.linear_acceleration = from_vector(sample.linear_acceleration());
  out.angular_velocity_variance = sample.angular_velocity_variance();
  out.linear_acceleration_variance = sample.linear_acceleration_variance();
  return out;
}

msg::SensorList to_msg(const std::vector<hardware::SensorInfo>& sensors, uint32_t model_version,
                       int64_t stamp_ns) {
  msg::SensorList out;
  out.model_version(model_version);
  out.stamp_ns(stamp_ns);
  for (const auto& s : sensors) {
    msg::SensorDescription d;
    d.name(s.name);
    d.kind(to_kind(s.type));
    d.frame(s.frame);
    d.rate(s.rate);
    out.sensors().push_back(std::move(d));
  }
  return out;
}

std::vector<hardware::SensorInfo> from_msg(const msg::SensorList& list) {
  std::vector<hardware::SensorInfo> out;
  for (const auto& d : list.sensors()) {
    out.push_back({d.name(), from_kind(d.kind(), d.name()), d.frame(), d.rate()});
  }
  return out;
}

}  // namespace concert::sensors_dds
