// SensorPublisher: what the backend's sensor threads hand over arrives on the sensor topics,
// field by field, through a real DDS reader; cameras are separate instances.
#include "sensor_publisher.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <map>

#include "concert/dds/catalogue.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/sensors_dds/conversions.hpp"
#include "synthetic_sensors.hpp"

namespace concert::robot::dds {
namespace {

using namespace std::chrono_literals;
namespace cdds = concert::dds;
namespace topics = concert::dds::topics;

template <class T>
void wait_matched(cdds::Reader<T>& reader) {
  ASSERT_TRUE(reader.wait_for_writers(1, 10s)) << "no writer matched";
}

TEST(SensorPublisher, RgbdFrameArrivesAsColourDepthAndInfo) {
  cdds::Participant participant({.name = "sensor_publisher_test"});
  SensorPublisher publisher(participant, 7);
  cdds::Reader<msg::Image> rgb(participant, topics::camera_rgb);
  cdds::Reader<msg::Image> depth(participant, topics::camera_depth);
  cdds::Reader<msg::CameraInfo> info(participant, topics::camera_info);
  wait_matched(rgb);
  wait_matched(depth);
  wait_matched(info);

  const auto frame = testing::synthetic_rgbd_frame("camera_E", 640, 480, 11);
  publisher.on_rgbd(frame);
  const auto got_rgb = rgb.wait(10s);
  const auto got_depth = depth.wait(10s);
  const auto got_info = info.wait(10s);
  ASSERT_TRUE(got_rgb && got_depth && got_info);
  EXPECT_EQ(got_rgb->sensor_id(), cdds::sensor_id("camera_E"));
  EXPECT_EQ(got_rgb->model_version(), 7u);
  EXPECT_EQ(got_rgb->stamp_ns(), 12'500'000'000);
  EXPECT_EQ(got_rgb->encoding(), "rgb8");
  EXPECT_EQ(got_depth->encoding(), "16UC1");
  EXPECT_EQ(got_depth->depth_scale(), 0.001);
  EXPECT_EQ(got_info->fx(), frame.intrinsics.fx);

  const hardware::RgbdFrame back = sensors_dds::to_rgbd_frame(*got_rgb, *got_depth, *got_info);
  EXPECT_EQ(back.sensor, frame.sensor);
  EXPECT_EQ(back.frame, frame.frame);
  EXPECT_EQ(back.stamp, frame.stamp);
  EXPECT_EQ(back.intrinsics, frame.intrinsics);
  EXPECT_TRUE(back.rgb == frame.rgb) << "colour pixels differ";
  EXPECT_TRUE(back.depth == frame.depth) << "depth pixels differ";
  EXPECT_EQ(back.depth_scale, frame.depth_scale);
  EXPECT_EQ(back.depth_min, frame.depth_min);
  EXPECT_EQ(back.depth_max, frame.depth_max);
  EXPECT_EQ(publisher.dropped(), 0u);
}

TEST(SensorPublisher, TwoCamerasAreTwoInstancesThatDoNotReplaceEachOther) {
  cdds::Participant participant({.name = "sensor_publisher_test"});
  SensorPublisher publisher(participant);
  cdds::Reader<msg::Image> rgb(participant, topics::camera_rgb);
  wait_matched(rgb);
  // Both written before anything is taken: with keep-last 1 per instance, both stay.
  publisher.on_rgbd(testing::synthetic_rgbd_frame("camera_E", 32, 24, 1));
  publisher.on_rgbd(testing::synthetic_rgbd_frame("camera_F", 32, 24, 2));
  std::map<std::string, msg::Image> got;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (got.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    if (auto s = rgb.wait(100ms)) got[s->sensor()] = *s;
  }
  ASSERT_EQ(got.size(), 2u) << "one camera's image replaced the other's";
  EXPECT_EQ(got.at("camera_E").data(), testing::synthetic_rgbd_frame("camera_E", 32, 24, 1).rgb);
  EXPECT_EQ(got.at("camera_F").data(), testing::synthetic_rgbd_frame("camera_F", 32, 24, 2).rgb);
  EXPECT_NE(got.at("camera_E").sensor_id(), got.at("camera_F").sensor_id());
}

TEST(SensorPublisher, LidarScanSonarImuArriveFieldByField) {
  cdds::Participant participant({.name = "sensor_publisher_test"});
  SensorPublisher publisher(participant, 3);
  cdds::Reader<msg::LidarScan> lidar(participant, topics::lidar);
  cdds::Reader<msg::LaserScan> scan(participant, topics::scan);
  cdds::Reader<msg::SonarRanges> sonar(participant, topics::sonar);
  cdds::Reader<msg::Imu> imu(participant, topics::imu);
  wait_matched(lidar);
  wait_matched(scan);
  wait_matched(sonar);
  wait_matched(imu);

  const auto lidar_in = testing::synthetic_lidar_scan("lidar_front_A", 16, 1800, 5);
  const hardware::LaserScan2d scan_in{
      "base_scan", 0.5, -3.1, 0.0087, std::vector<float>(720, 4.5f), 0.1f, 30.0f};
  const hardware::SonarRanges sonar_in{0.75,
                                       {{"sonar_1", "sonar_1_link", 1.25f, 0.02f, 4.0f, 0.5f}}};
  hardware::ImuSample imu_in;
  imu_in.sensor = "imu_base";
  imu_in.frame = "base_link";
  imu_in.stamp = 0.002;
  imu_in.angular_velocity = {0.01, 0.02, -0.03};
  imu_in.linear_acceleration = {0.1, -0.2, 9.79};
  imu_in.angular_velocity_variance = 3e-6;
  imu_in.linear_acceleration_variance = 2e-4;
  publisher.on_lidar(lidar_in);
  publisher.on_scan2d(scan_in);
  publisher.on_sonars(sonar_in);
  publisher.on_imu(imu_in);

  const auto l = lidar.wait(10s);
  ASSERT_TRUE(l);
  EXPECT_EQ(l->model_version(), 3u);
  const auto lb = sensors_dds::from_msg(*l);
  EXPECT_EQ(lb.sensor, lidar_in.sensor);
  EXPECT_EQ(lb.elevations, lidar_in.elevations);
  EXPECT_EQ(lb.ranges, lidar_in.ranges);
  EXPECT_EQ(lb.columns, lidar_in.columns);
  EXPECT_EQ(lb.azimuth_increment, lidar_in.azimuth_increment);

  const auto s = scan.wait(10s);
  ASSERT_TRUE(s);
  const auto sb = sensors_dds::from_msg(*s);
  EXPECT_EQ(sb.frame, scan_in.frame);
  EXPECT_EQ(sb.ranges, scan_in.ranges);
  EXPECT_EQ(sb.angle_min, scan_in.angle_min);

  const auto so = sonar.wait(10s);
  ASSERT_TRUE(so);
  const auto sob = sensors_dds::from_msg(*so);
  ASSERT_EQ(sob.sonars.size(), 1u);
  EXPECT_EQ(sob.sonars[0].sensor, "sonar_1");
  EXPECT_EQ(sob.sonars[0].range, 1.25f);
  EXPECT_EQ(sob.stamp, 0.75);

  const auto i = imu.wait(10s);
  ASSERT_TRUE(i);
  EXPECT_EQ(i->sensor_id(), cdds::sensor_id("imu_base"));
  const auto ib = sensors_dds::from_msg(*i);
  EXPECT_EQ(ib.angular_velocity, imu_in.angular_velocity);
  EXPECT_EQ(ib.linear_acceleration, imu_in.linear_acceleration);
  EXPECT_EQ(ib.angular_velocity_variance, imu_in.angular_velocity_variance);
  EXPECT_EQ(ib.linear_acceleration_variance, imu_in.linear_acceleration_variance);
}

TEST(SensorPublisher, SensorListIsLatchedAndFollowsTheModelVersion) {
  cdds::Participant participant({.name = "sensor_publisher_test"});
  SensorPublisher publisher(participant, 2);
  const std::vector<hardware::SensorInfo> mounted = {
      {"camera_E", hardware::SensorType::kRgbd, "camera_E_optical", 15.0},
      {"lidar_front_A", hardware::SensorType::kLidar, "lidar_front_A", 10.0}};
  publisher.on_sensors(mounted);
  // A reader that comes later still gets the list (transient-local).
  cdds::Reader<msg::SensorList> list(participant, topics::sensor_list);
  const auto first = list.wait(10s);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->model_version(), 2u);
  EXPECT_EQ(sensors_dds::from_msg(*first), mounted);

  publisher.set_model_version(2);  // unchanged: nothing new
  publisher.set_model_version(3);
  const auto second = list.wait(10s);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->model_version(), 3u);
  EXPECT_EQ(sensors_dds::from_msg(*second), mounted);
  EXPECT_FALSE(list.take().has_value());
}

TEST(SensorPublisher, MalformedFramesAreDroppedAndCountedNotThrown) {
  cdds::Participant participant({.name = "sensor_publisher_test"});
  SensorPublisher publisher(participant);
  auto frame = testing::synthetic_rgbd_frame("camera_E", 8, 8, 1);
  frame.rgb.resize(5);
  EXPECT_NO_THROW(publisher.on_rgbd(frame));
  EXPECT_EQ(publisher.dropped(), 1u);  // the colour image; depth and info went out
}

}  // namespace
}  // namespace concert::robot::dds
