#pragma once
// Parameters of the simulated sensors: the devices of the real CONCERT robot (paper §3; the
// mobile platform's set in concert_resources/sensors/mobile_platform_sensors.yaml), with the
// noise their makers state. Every number has its source next to it; "estimate" marks a
// plausible value where no source gives one. Rates are in simulated time.

#include <cstdint>
#include <string>

#include "concert/hardware/sensors.hpp"

namespace concert::sim {

/// A sensor of the simulated robot: which device, at which URDF link (a sensor frame of the
/// robot model; see hardware/sensors.hpp for the frame conventions).
struct SensorMount {
  std::string name;   ///< model sensor name (unique)
  hardware::SensorType type{hardware::SensorType::kRgbd};
  std::string frame;  ///< URDF link
  bool operator==(const SensorMount&) const = default;
};

/// Intel RealSense D435i, colour stream at 640 x 480 with depth aligned to it (the drill's
/// camera in the paper, and the platform's front and back cameras).
struct CameraParams {
  double rate{15.0};           ///< [Hz]
  std::uint32_t width{640};    ///< [px]
  std::uint32_t height{480};   ///< [px]
  /// [px] focal length, fx = fy (square pixels); cx, cy at the image centre. A D435i's colour
  /// stream at 640 x 480 reports fx ≈ fy ≈ 615 px (≈ 55° x 43° field of view).
  double focal{615.0};
  double depth_min{0.105};     ///< [m] D435 minimum depth at 848 x 480 (datasheet: ~0.105 m)
  double depth_max{10.0};      ///< [m] datasheet: ~10 m, varies with light and texture
  /// Depth noise: zero-mean Gaussian with the RMS error of Intel's D400 model,
  /// RMS(z) = z^2 * subpixel / (focal_depth * baseline) (Intel RealSense D400 series datasheet
  /// and "Tuning depth cameras for best performance": subpixel 0.08 typical, baseline 50 mm,
  /// depth imager focal ≈ 423 px at 848 x 480 for its 87° field of view): 1.4 mm at 0.6 m,
  /// 15 mm at 2 m (the datasheet bounds it at ≤ 2 % at 2 m).
  double depth_subpixel{0.08};
  double depth_baseline{0.050};   ///< [m]
  double depth_focal{423.0};      ///< [px]
  double rgb_noise{2.0};          ///< std-dev of the per-channel colour noise [0..255] (estimate)
  bool noise{true};
};

/// Velodyne VLP-16 (datasheet: 16 channels over ±15°, 360°, range up to 100 m, accuracy
/// ±3 cm typical, 5–20 Hz, 0.1°–0.4° horizontal resolution).
struct LidarParams {
  double rate{10.0};              ///< [Hz] (datasheet 5–20 Hz)
  std::uint32_t rings{16};
  double elevation_min{-0.2617993877991494};  ///< [rad] -15°
  double elevation_max{0.2617993877991494};   ///< [rad] +15°
  std::uint32_t columns{900};     ///< per revolution: 0.4° (the datasheet's resolution at 20 Hz)
  double range_min{0.1};          ///< [m]
  double range_max{100.0};        ///< [m]
  double range_noise{0.015};      ///< std-dev [m]: "±3 cm typical" read as 2 sigma
  bool noise{true};
};

/// The planar scan navigation reads, derived from every lidar: returns whose height above the
/// floor lies in [height_min, height_max] (what the base could hit), binned by bearing about
/// the root link's z axis, nearest per bin.
struct Scan2dParams {
  std::uint32_t bins{720};     ///< over 360° (0.5°)
  double height_min{0.05};     ///< [m] above the floor: lower returns are the floor
  double height_max{2.0};      ///< [m] above the floor
  double range_max{30.0};      ///< [m]
};

/// Ultrasound range sensors of the platform (model not in the public data: values of a
/// typical industrial ultrasound sensor, estimate).
struct SonarParams {
  double rate{20.0};             ///< [Hz]
  double range_min{0.2};         ///< [m]
  double range_max{4.0};         ///< [m]
  double field_of_view{0.5236};  ///< full cone angle [rad] (30°)
  double range_noise{0.01};      ///< std-dev [m]
  std::uint32_t rays{25};        ///< rays sampling the cone (axis + rings)
  bool noise{true};
};

/// IMU (the D435i's Bosch BMI055 datasheet: gyroscope noise density 0.014 °/s/√Hz, accelerometer
/// 150 µg/√Hz; zero-rate offset ±1 °/s, zero-g offset ±70 mg: the initial bias is drawn with a
/// third of those as std-dev; bias random walk: estimate).
struct ImuParams {
  double rate{200.0};                       ///< [Hz]
  double gyro_noise_density{2.44e-4};       ///< [rad/s/√Hz]
  double accel_noise_density{1.47e-3};      ///< [m/s^2/√Hz]
  double gyro_bias_sigma{5.8e-3};           ///< [rad/s] initial bias std-dev
  double accel_bias_sigma{0.23};            ///< [m/s^2] initial bias std-dev
  double gyro_bias_walk{1e-5};              ///< [rad/s^2/√Hz] (estimate)
  double accel_bias_walk{1e-4};             ///< [m/s^3/√Hz] (estimate)
  bool noise{true};
};

/// Every simulated sensor.
struct SensorParams {
  bool enabled{true};  ///< false: no sensor runs (the joints only)
  CameraParams camera;
  LidarParams lidar;
  Scan2dParams scan2d;
  SonarParams sonar;
  ImuParams imu;
  unsigned seed{1};    ///< noise seed (each sensor derives its own stream from it and its name)
};

/// The rate [Hz] of sensors of `type`.
constexpr double sensor_rate(const SensorParams& p, hardware::SensorType type) {
  switch (type) {
    case hardware::SensorType::kRgbd:
      return p.camera.rate;
    case hardware::SensorType::kLidar:
      return p.lidar.rate;
    case hardware::SensorType::kSonar:
      return p.sonar.rate;
    case hardware::SensorType::kImu:
      return p.imu.rate;
  }
  return 0.0;
}

}  // namespace concert::sim
