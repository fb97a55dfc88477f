// `concert camera list|snapshot` against a test publisher of known synthetic RGB-D frames (two
// cameras), and `concert topic list|hz` on the image topics (1 MB samples through the
// schema-driven codec).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/sensors_dds/conversions.hpp"
#include "process.hpp"
#include "synthetic_sensors.hpp"

namespace concert {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
namespace topics = dds::topics;

testing::Outcome concert_cli(std::vector<std::string> args) {
  args.insert(args.begin(), CONCERT_BIN);
  return testing::run(args, 60s);
}

/// Publishes a 640x480 frame of camera_E and a smaller one of camera_F every 50 ms (the same
/// pixels each time), and the sensor list naming both, until destroyed.
class CameraPublisher {
 public:
  CameraPublisher()
      : rgb_(participant_, topics::camera_rgb),
        depth_(participant_, topics::camera_depth),
        info_(participant_, topics::camera_info),
        list_(participant_, topics::sensor_list) {
    list_.write(
        sensors_dds::to_msg({{"camera_E", hardware::SensorType::kRgbd, "camera_E_optical", 20.0},
                             {"lidar_A", hardware::SensorType::kLidar, "lidar_A", 10.0},
                             {"camera_F", hardware::SensorType::kRgbd, "camera_F_optical", 20.0}},
                            6, now_ns()));
    thread_ = std::thread([this] {
      while (!stop_) {
        for (const auto* f : {&e_, &f_}) {
          msg::Image rgb, depth;
          sensors_dds::to_rgb_image(*f, 6, rgb);
          sensors_dds::to_depth_image(*f, 6, depth);
          rgb_.write(rgb);
          depth_.write(depth);
          info_.write(sensors_dds::to_camera_info(*f, 6));
        }
        std::this_thread::sleep_for(50ms);
      }
    });
  }
  ~CameraPublisher() {
    stop_ = true;
    thread_.join();
  }

  const hardware::RgbdFrame e_ = testing::synthetic_rgbd_frame("camera_E", 640, 480, 31, 4.25);
  const hardware::RgbdFrame f_ = testing::synthetic_rgbd_frame("camera_F", 64, 48, 32, 4.25);

 private:
  dds::Participant participant_{{.name = "camera_cli_test"}};
  dds::Writer<msg::Image> rgb_;
  dds::Writer<msg::Image> depth_;
  dds::Writer<msg::CameraInfo> info_;
  dds::Writer<msg::SensorList> list_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(CameraCli, SnapshotWritesPngsThatReadBackEqual) {
  CameraPublisher publisher;
  testing::TempDir dir("camera-snapshot");
  const auto r =
      concert_cli({"camera", "snapshot", "--out", dir.path() + "/shots", "--timeout", "20"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  // Without --camera: the sensor list's first camera.
  EXPECT_THAT(r.out, HasSubstr("camera camera_E (frame camera_E_optical, model version 6)"));
  EXPECT_THAT(r.out, HasSubstr("640 x 480 px"));
  EXPECT_THAT(r.out, HasSubstr("4250000000 ns"));
  const std::string rgb_path = dir.path() + "/shots/camera_E_rgb.png";
  const std::string depth_path = dir.path() + "/shots/camera_E_depth.png";
  EXPECT_THAT(r.out, HasSubstr(rgb_path));

  const cv::Mat bgr = cv::imread(rgb_path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  ASSERT_EQ(bgr.cols, 640);
  ASSERT_EQ(bgr.rows, 480);
  const auto& e = publisher.e_;
  size_t differing = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const auto px = bgr.at<cv::Vec3b>(v, u);
      const size_t i = (static_cast<size_t>(v) * 640 + u) * 3;
      differing += px[2] != e.rgb[i] || px[1] != e.rgb[i + 1] || px[0] != e.rgb[i + 2];
    }
  }
  EXPECT_EQ(differing, 0u) << "colour pixels differ from the published frame";

  const cv::Mat depth = cv::imread(depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(depth.type(), CV_16UC1);
  ASSERT_EQ(depth.total(), e.depth.size());
  EXPECT_TRUE(std::equal(e.depth.begin(), e.depth.end(), depth.ptr<uint16_t>()))
      << "depth pixels differ from the published frame";

  const auto json = concert_cli({"camera", "snapshot", "--camera", "camera_F", "--out", dir.path(),
                                 "--json", "--timeout", "20"});
  ASSERT_EQ(json.code, 0) << json.err;
  const auto j = idl::Json::parse(json.out);
  EXPECT_EQ(j.at("camera"), "camera_F");
  EXPECT_EQ(j.at("width"), 64);
  EXPECT_DOUBLE_EQ(j.at("fx").get<double>(), publisher.f_.intrinsics.fx);
  const auto [lo, hi] = std::minmax_element(publisher.f_.depth.begin(), publisher.f_.depth.end());
  EXPECT_DOUBLE_EQ(j.at("depth_min_seen").get<double>(), *lo * 0.001);
  EXPECT_DOUBLE_EQ(j.at("depth_max_seen").get<double>(), *hi * 0.001);
  EXPECT_TRUE(std::filesystem::exists(dir.path() + "/camera_F_depth.png"));
}

TEST(CameraCli, UnknownCameraFailsListingTheRobotsCameras) {
  CameraPublisher publisher;
  const auto r = concert_cli({"camera", "snapshot", "--camera", "camera_Z", "--timeout", "20"});
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_THAT(r.err,
              HasSubstr("no camera 'camera_Z' on the robot; its cameras: camera_E, camera_F"));
}

TEST(CameraCli, ListShowsTheCamerasOfTheSensorList) {
  CameraPublisher publisher;
  const auto r = concert_cli({"camera", "list", "--timeout", "10"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 cameras at model version 6"));
  EXPECT_THAT(r.out, HasSubstr("camera_E  frame camera_E_optical  20 Hz"));
  EXPECT_THAT(r.out, HasSubstr("camera_F"));
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("lidar_A")));
}

TEST(CameraCli, TopicVerbsHandleTheImageTopics) {
  CameraPublisher publisher;
  const auto hz = concert_cli(
      {"topic", "hz", "concert/sensors/camera/rgb", "--count", "10", "--timeout", "20", "--json"});
  ASSERT_EQ(hz.code, 0) << hz.out << hz.err;
  EXPECT_GT(idl::Json::parse(testing::lines(hz.out).back()).at("rate_hz").get<double>(), 0.0);
  const auto depth_hz = concert_cli(
      {"topic", "hz", "concert/sensors/camera/depth", "--count", "5", "--timeout", "20", "--json"});
  EXPECT_EQ(depth_hz.code, 0) << depth_hz.err;
  const auto list = concert_cli({"topic", "list", "--timeout", "2"});
  ASSERT_EQ(list.code, 0) << list.err;
  for (const char* t : {"concert/sensors/camera/rgb", "concert/sensors/camera/depth",
                        "concert/sensors/camera/info", "concert/sensors/list"}) {
    EXPECT_THAT(list.out, HasSubstr(t));
  }
}

TEST(CameraCli, NoPublisherTimesOutNamingTheTopic) {
  const auto r = concert_cli({"camera", "snapshot", "--timeout", "1"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("no camera publishes on concert/sensors/camera/rgb within 1 s"));
  const auto named = concert_cli({"camera", "snapshot", "--camera", "camera_E", "--timeout", "1"});
  EXPECT_EQ(named.code, 1);
  EXPECT_THAT(named.err, HasSubstr("no complete frame of camera 'camera_E'"));
  EXPECT_THAT(named.err, HasSubstr("cameras seen: none"));
  const auto list = concert_cli({"camera", "list", "--timeout", "1"});
  EXPECT_EQ(list.code, 1);
  EXPECT_THAT(list.err, HasSubstr("no sensor list on concert/sensors/list within 1 s"));
}

}  // namespace
}  // namespace concert
