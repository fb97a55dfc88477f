#include "concert/sensors_dds/conversions.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "concert/dds/catalogue.hpp"
#include "synthetic_sensors.hpp"

namespace concert::sensors_dds {
namespace {

using ::testing::HasSubstr;

TEST(Camera, ColourDepthAndInfoRoundTripToTheSameFrame) {
  const auto frame = testing::synthetic_rgbd_frame("camera_E", 64, 48, 7);
  msg::Image rgb, depth;
  to_rgb_image(frame, 4, rgb);
  to_depth_image(frame, 4, depth);
  const msg::CameraInfo info = to_camera_info(frame, 4);
  EXPECT_EQ(rgb.sensor_id(), dds::sensor_id("camera_E"));
  EXPECT_EQ(depth.sensor_id(), rgb.sensor_id());
  EXPECT_EQ(rgb.encoding(), "rgb8");
  EXPECT_EQ(rgb.step(), 64u * 3);
  EXPECT_EQ(depth.encoding(), "16UC1");
  EXPECT_EQ(depth.step(), 64u * 2);
  EXPECT_EQ(depth.data().size(), 64u * 48 * 2);
  // Little-endian uint16: low byte first.
  EXPECT_EQ(depth.data()[0], frame.depth[0] & 0xff);
  EXPECT_EQ(depth.data()[1], frame.depth[0] >> 8);
  EXPECT_EQ(rgb.stamp_ns(), 12'500'000'000);
  EXPECT_EQ(rgb.model_version(), 4u);
  EXPECT_EQ(info.distortion_model(), "none");
  EXPECT_TRUE(info.distortion().empty());

  const hardware::RgbdFrame back = to_rgbd_frame(rgb, depth, info);
  EXPECT_EQ(back.sensor, frame.sensor);
  EXPECT_EQ(back.frame, frame.frame);
  EXPECT_DOUBLE_EQ(back.stamp, frame.stamp);
  EXPECT_EQ(back.intrinsics, frame.intrinsics);
  EXPECT_EQ(back.rgb, frame.rgb);
  EXPECT_EQ(back.depth, frame.depth);
  EXPECT_DOUBLE_EQ(back.depth_scale, frame.depth_scale);
  EXPECT_FLOAT_EQ(back.depth_min, frame.depth_min);
  EXPECT_FLOAT_EQ(back.depth_max, frame.depth_max);
}

TEST(Camera, PaddedRowsAreReadByStep) {
  const auto frame = testing::synthetic_rgbd_frame("cam", 5, 3, 1);
  msg::Image rgb, depth;
  to_rgb_image(frame, 1, rgb);
  to_depth_image(frame, 1, depth);
  // Re-pack the colour rows with 4 bytes of padding each, as some drivers do.
  std::vector<uint8_t> padded;
  for (uint32_t v = 0; v < 3; ++v) {
    padded.insert(padded.end(), rgb.data().begin() + v * 15, rgb.data().begin() + (v + 1) * 15);
    padded.insert(padded.end(), 4, 0xee);
  }
  rgb.data(padded);
  rgb.step(19);
  EXPECT_EQ(to_rgbd_frame(rgb, depth, to_camera_info(frame, 1)).rgb, frame.rgb);
}

TEST(Camera, MalformedImagesAreRefusedNamingTheCamera) {
  auto frame = testing::synthetic_rgbd_frame("camera_E", 8, 6, 2);
  msg::Image rgb, depth;
  to_rgb_image(frame, 1, rgb);
  to_depth_image(frame, 1, depth);
  const auto info = to_camera_info(frame, 1);

  msg::Image short_rgb = rgb;
  short_rgb.data().pop_back();
  try {
    to_rgbd_frame(short_rgb, depth, info);
    FAIL() << "a short image was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("camera 'camera_E'"));
    EXPECT_THAT(e.what(), HasSubstr("143 bytes, not step * height = 144"));
  }
  EXPECT_THROW(to_rgbd_frame(depth, rgb, info), std::invalid_argument);  // encodings swapped
  msg::Image late = depth;
  late.stamp_ns(late.stamp_ns() + 1);
  EXPECT_THROW(to_rgbd_frame(rgb, late, info), std::invalid_argument);
  msg::Image other = depth;
  other.sensor("camera_F");
  EXPECT_THROW(to_rgbd_frame(rgb, other, info), std::invalid_argument);

  frame.rgb.pop_back();
  EXPECT_THROW(to_rgb_image(frame, 1, rgb), std::invalid_argument);
  frame.depth.pop_back();
  EXPECT_THROW(to_depth_image(frame, 1, depth), std::invalid_argument);
}

TEST(Camera, DepthFramesComeWithoutColourAndRefuseAnotherEncodingOrCamera) {
  const auto frame = testing::synthetic_rgbd_frame("camera_E", 8, 6, 3);
  msg::Image rgb, depth;
  to_rgb_image(frame, 1, rgb);
  to_depth_image(frame, 1, depth);
  const auto info = to_camera_info(frame, 1);
  const hardware::RgbdFrame back = to_depth_frame(depth, info);
  EXPECT_EQ(back.sensor, frame.sensor);
  EXPECT_EQ(back.intrinsics, frame.intrinsics);
  EXPECT_EQ(back.depth, frame.depth);
  EXPECT_TRUE(back.rgb.empty());
  EXPECT_DOUBLE_EQ(back.depth_scale, frame.depth_scale);
  try {
    (void)to_depth_frame(rgb, info);
    FAIL() << "a colour image was read as depth";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("camera 'camera_E': image encoding is 'rgb8', expected '16UC1'"));
  }
  auto other = info;
  other.sensor("camera_F");
  EXPECT_THROW((void)to_depth_frame(depth, other), std::invalid_argument);
  auto smaller = info;
  smaller.width(4);
  EXPECT_THROW((void)to_depth_frame(depth, smaller), std::invalid_argument);
}

TEST(Camera, ReusedBuffersTakeTheNewFrame) {
  msg::Image rgb;
  to_rgb_image(testing::synthetic_rgbd_frame("cam", 16, 16, 1), 1, rgb);
  const auto second = testing::synthetic_rgbd_frame("cam", 8, 4, 2);
  to_rgb_image(second, 2, rgb);
  EXPECT_EQ(rgb.data(), second.rgb);
  EXPECT_EQ(rgb.width(), 8u);
  EXPECT_EQ(rgb.model_version(), 2u);
}

TEST(Lidar, RoundTripsAndRefusesRangesOfTheWrongSize) {
  const auto scan = testing::synthetic_lidar_scan("lidar_front_A", 16, 90, 3);
  msg::LidarScan m = to_msg(scan, 2);
  EXPECT_EQ(m.sensor_id(), dds::sensor_id("lidar_front_A"));
  const auto back = from_msg(m);
  EXPECT_EQ(back.sensor, scan.sensor);
  EXPECT_EQ(back.frame, scan.frame);
  EXPECT_DOUBLE_EQ(back.stamp, scan.stamp);
  EXPECT_EQ(back.elevations, scan.elevations);
  EXPECT_DOUBLE_EQ(back.azimuth_min, scan.azimuth_min);
  EXPECT_DOUBLE_EQ(back.azimuth_increment, scan.azimuth_increment);
  EXPECT_EQ(back.columns, scan.columns);
  EXPECT_EQ(back.ranges, scan.ranges);
  EXPECT_EQ(back.range_min, scan.range_min);
  EXPECT_EQ(back.range_max, scan.range_max);
  m.ranges().pop_back();
  EXPECT_THROW(from_msg(m), std::invalid_argument);
}

TEST(Scan2d, SonarImuAndSensorListRoundTrip) {
  hardware::LaserScan2d scan{
      "base_scan", 1.5,  -2.0, 0.01, {1.0f, std::numeric_limits<float>::infinity(), 2.5f},
      0.1f,        30.0f};
  const auto scan_back = from_msg(to_msg(scan, 1));
  EXPECT_EQ(scan_back.frame, scan.frame);
  EXPECT_EQ(scan_back.ranges, scan.ranges);
  EXPECT_DOUBLE_EQ(scan_back.angle_min, scan.angle_min);
  EXPECT_DOUBLE_EQ(scan_back.angle_increment, scan.angle_increment);
  EXPECT_EQ(scan_back.range_max, scan.range_max);

  hardware::SonarRanges sonars{
      2.0,
      {{"sonar_1", "sonar_1_link", 1.2f, 0.02f, 4.0f, 0.5f},
       {"sonar_2", "sonar_2_link", std::numeric_limits<float>::infinity(), 0.02f, 4.0f, 0.5f}}};
  const auto sonars_back = from_msg(to_msg(sonars, 1));
  ASSERT_EQ(sonars_back.sonars.size(), 2u);
  EXPECT_EQ(sonars_back.sonars[1].sensor, "sonar_2");
  EXPECT_EQ(sonars_back.sonars[1].range, sonars.sonars[1].range);
  EXPECT_EQ(sonars_back.sonars[0].field_of_view, 0.5f);

  hardware::ImuSample imu;
  imu.sensor = "imu_base";
  imu.frame = "base_link";
  imu.stamp = 0.001;
  imu.angular_velocity = {0.1, -0.2, 0.3};
  imu.linear_acceleration = {0.0, 0.1, 9.81};
  imu.angular_velocity_variance = 1e-6;
  imu.linear_acceleration_variance = 4e-4;
  const msg::Imu m = to_msg(imu, 5);
  EXPECT_EQ(m.sensor_id(), dds::sensor_id("imu_base"));
  const auto imu_back = from_msg(m);
  EXPECT_EQ(imu_back.angular_velocity, imu.angular_velocity);
  EXPECT_EQ(imu_back.linear_acceleration, imu.linear_acceleration);
  EXPECT_EQ(imu_back.linear_acceleration_variance, imu.linear_acceleration_variance);
  EXPECT_EQ(imu_back.stamp, imu.stamp);

  const std::vector<hardware::SensorInfo> mounted = {
      {"camera_E", hardware::SensorType::kRgbd, "camera_E_optical", 15},
      {"lidar_A", hardware::SensorType::kLidar, "lidar_A", 10},
      {"sonar_1", hardware::SensorType::kSonar, "sonar_1_link", 20},
      {"imu", hardware::SensorType::kImu, "base_link", 200}};
  const msg::SensorList list = to_msg(mounted, 3, 42);
  EXPECT_EQ(list.model_version(), 3u);
  EXPECT_EQ(list.sensors()[2].kind(), msg::SENSOR_SONAR);
  EXPECT_EQ(from_msg(list), mounted);
}

TEST(SensorId, IsFnv1aOfTheNameAndTellsCamerasApart) {
  EXPECT_EQ(dds::sensor_id(""), 2166136261u);
  EXPECT_EQ(dds::sensor_id("a"), 0xe40c292cu);  // FNV-1a 32 reference value
  EXPECT_NE(dds::sensor_id("camera_E"), dds::sensor_id("camera_F"));
}

}  // namespace
}  // namespace concert::sensors_dds
