#pragma once
// What the robot's exteroceptive and inertial sensors measure, as plain C++ (no DDS): RGB-D
// cameras, 3D lidars (and the 2D scan navigation derives from them), ultrasound range sensors,
// IMUs. A backend that has sensors hands their data to a SensorSink from its own threads
// (never from the control thread); the robot service's DDS adapter is such a sink.
//
// Frames: every sample names the URDF link it is measured in (a sensor frame of the robot
// model). Camera frames are optical frames: z along the optical axis, x to the right of the
// image, y down. Lidar and sonar frames: x is the beam/cone axis at azimuth 0; lidar rings
// are at elevations about the frame's xy plane. IMU axes are the frame's axes.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace concert::hardware {

/// What a sensor is.
enum class SensorType : std::uint8_t { kRgbd, kLidar, kSonar, kImu };
/// "rgbd", "lidar", "sonar", "imu".
constexpr std::string_view to_string(SensorType type) {
  switch (type) {
    case SensorType::kRgbd:
      return "rgbd";
    case SensorType::kLidar:
      return "lidar";
    case SensorType::kSonar:
      return "sonar";
    case SensorType::kImu:
      return "imu";
  }
  return "unknown";
}

/// One mounted sensor.
struct SensorInfo {
  std::string name;   ///< model sensor name, e.g. "camera_E", "lidar_front_A"
  SensorType type{SensorType::kRgbd};
  std::string frame;  ///< URDF link the data is measured in
  double rate{0.0};   ///< [Hz] at which it produces data
  bool operator==(const SensorInfo&) const = default;
};

/// Pinhole intrinsics of an image (no distortion: the simulated lens is ideal; a real
/// RealSense publishes Brown-Conrady coefficients that are close to zero).
struct CameraIntrinsics {
  std::uint32_t width{0};
  std::uint32_t height{0};
  double fx{0.0};  ///< [px]
  double fy{0.0};  ///< [px]
  double cx{0.0};  ///< [px], principal point; pixel (u, v) has its centre at (u, v)
  double cy{0.0};  ///< [px]
  bool operator==(const CameraIntrinsics&) const = default;
};

/// One aligned RGB + depth frame (depth registered to the colour image, as a RealSense's
/// "align to colour" gives): pixel (u, v) of both images sees the same ray.
struct RgbdFrame {
  std::string sensor;
  std::string frame;        ///< optical frame
  double stamp{0.0};        ///< [s], hardware clock (simulated time in simulation)
  CameraIntrinsics intrinsics;
  std::vector<std::uint8_t> rgb;     ///< RGB8, row-major, top row first: width * height * 3
  std::vector<std::uint16_t> depth;  ///< z along the optical axis [mm] (RealSense z16, scale 0.001); 0 = no data
  double depth_scale{0.001};         ///< [m] per depth unit
  float depth_min{0.0f};             ///< [m] nearer is reported as 0 (no data)
  float depth_max{0.0f};             ///< [m] farther is reported as 0 (no data)
};

/// One revolution of a multi-beam lidar, organised as rings x columns.
struct LidarScan {
  std::string sensor;
  std::string frame;
  double stamp{0.0};                   ///< [s] (the whole revolution is taken at one instant)
  std::vector<float> elevations;       ///< [rad] per ring, about the frame's xy plane
  double azimuth_min{0.0};             ///< [rad] of column 0 (about the frame's z, from x)
  double azimuth_increment{0.0};       ///< [rad] between columns
  std::uint32_t columns{0};
  std::vector<float> ranges;           ///< [m], ring-major (ring r, column c at r * columns + c); 0 = no return
  float range_min{0.0f};               ///< [m]
  float range_max{0.0f};               ///< [m]
};

/// A planar scan (what navigation reads), about the frame's z axis, like ROS's LaserScan.
struct LaserScan2d {
  std::string frame;
  double stamp{0.0};
  double angle_min{0.0};        ///< [rad]
  double angle_increment{0.0};  ///< [rad]
  std::vector<float> ranges;    ///< [m]; +inf = nothing within range_max
  float range_min{0.0f};
  float range_max{0.0f};
};

/// One ultrasound reading: the nearest echo within the cone.
struct SonarRange {
  std::string sensor;
  std::string frame;           ///< x along the cone axis
  float range{0.0f};           ///< [m]; +inf = no echo within range_max
  float range_min{0.0f};       ///< [m]
  float range_max{0.0f};       ///< [m]
  float field_of_view{0.0f};   ///< full cone angle [rad]
};

/// Every ultrasound sensor of the robot, read at the same instant.
struct SonarRanges {
  double stamp{0.0};
  std::vector<SonarRange> sonars;
};

/// One IMU sample: what a MEMS IMU measures (no orientation estimate).
struct ImuSample {
  std::string sensor;
  std::string frame;
  double stamp{0.0};
  Eigen::Vector3d angular_velocity{Eigen::Vector3d::Zero()};     ///< [rad/s], sensor axes
  Eigen::Vector3d linear_acceleration{Eigen::Vector3d::Zero()};  ///< specific force [m/s^2] (reads +g up at rest)
  double angular_velocity_variance{0.0};     ///< [(rad/s)^2] per axis, of the white noise
  double linear_acceleration_variance{0.0};  ///< [(m/s^2)^2] per axis
};

/// Receives sensor data; called from the backend's sensor threads (any thread but the control
/// thread), possibly concurrently for different sensor types. Implementations must not block
/// for long: a slow sink makes the backend skip samples, never the control loop.
class SensorSink {
 public:
  virtual ~SensorSink() = default;
  /// The mounted sensors changed (start-up, hot swap): what produces data from now on.
  virtual void on_sensors(const std::vector<SensorInfo>& /*mounted*/) {}
  virtual void on_rgbd(const RgbdFrame& /*frame*/) {}
  virtual void on_lidar(const LidarScan& /*scan*/) {}
  virtual void on_scan2d(const LaserScan2d& /*scan*/) {}
  virtual void on_sonars(const SonarRanges& /*ranges*/) {}
  virtual void on_imu(const ImuSample& /*sample*/) {}
};

}  // namespace concert::hardware
