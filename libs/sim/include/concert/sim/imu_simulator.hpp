#pragma once
// Simulated MEMS IMU: MuJoCo gives the true angular velocity and specific force at a site of the
// IMU's body (a <gyro> and an <accelerometer> sensor on it); ImuSimulator adds what a real IMU
// adds to them (white noise, a constant bias, a bias random walk).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string>

#include "concert/hardware/sensors.hpp"
#include "concert/sim/sensor_params.hpp"

struct mjModel_;
struct mjData_;

namespace concert::sim {

/// Noise model of a MEMS IMU, per axis and independently for the gyroscope and the
/// accelerometer (the Kalibr / Allan-variance convention, continuous-time densities in
/// ImuParams):
///  * white noise: discrete std-dev σ_d = noise_density · √rate per sample (rate = params.rate,
///    the IMU's own output rate);
///  * bias: drawn once at construction from N(0, bias_sigma²), then a random walk with
///    per-sample step N(0, (bias_walk · √dt)²);
///  * measured = true + bias + white noise.
/// params.noise = false: the true values, zero bias, zero variances.
class ImuSimulator {
 public:
  /// Throws std::invalid_argument naming the parameter (rate <= 0, negative densities).
  ImuSimulator(const ImuParams& params, std::uint64_t seed);

  /// One sample from the true angular velocity [rad/s] and specific force [m/s²] in the sensor
  /// axes, `dt` [s] after the previous sample (the bias walk's step; >= 0). Fills
  /// angular_velocity, linear_acceleration and the white-noise variances σ_d²; sensor, frame and
  /// stamp are the caller's. Throws std::invalid_argument if dt is negative or not finite.
  void sample(const Eigen::Vector3d& true_angular_velocity,
              const Eigen::Vector3d& true_specific_force, double dt, hardware::ImuSample& out);

  /// Current biases (ground truth for tests and estimators).
  [[nodiscard]] const Eigen::Vector3d& gyro_bias() const { return gyro_bias_; }
  [[nodiscard]] const Eigen::Vector3d& accel_bias() const { return accel_bias_; }
  /// Discrete white-noise std-devs σ_d [rad/s], [m/s²].
  [[nodiscard]] double gyro_sigma() const { return gyro_sigma_; }
  [[nodiscard]] double accel_sigma() const { return accel_sigma_; }

 private:
  Eigen::Vector3d gaussian(double sigma);

  ImuParams params_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  Eigen::Vector3d gyro_bias_{Eigen::Vector3d::Zero()};
  Eigen::Vector3d accel_bias_{Eigen::Vector3d::Zero()};
  double gyro_sigma_{0.0};
  double accel_sigma_{0.0};
};

/// MJCF that makes MuJoCo measure an IMU's true values (see imu_mjcf()).
struct ImuMjcf {
  /// `<site name="NAME" .../>`: insert as a child of the <body> of the IMU's link.
  std::string site;
  /// `<gyro name="NAME_gyro" .../>` and `<accelerometer name="NAME_accel" .../>` on that site:
  /// insert inside the model's top-level <sensor> element.
  std::string sensors;
};

/// MJCF for the IMU called `sensor_name` at `body_T_imu` in its body's frame (a MuJoCo body built
/// from a URDF link has that link's frame). The caller inserts both parts (ImuMjcf) and
/// reads the values with ImuTruthReader.
ImuMjcf imu_mjcf(const std::string& sensor_name,
                 const Eigen::Isometry3d& body_T_imu = Eigen::Isometry3d::Identity());

/// True IMU values from MuJoCo, in the site's axes.
struct ImuTruth {
  Eigen::Vector3d angular_velocity{Eigen::Vector3d::Zero()};  ///< [rad/s] of the site's body
  /// [m/s²] specific force: the site's acceleration minus gravity (MuJoCo's accelerometer reads
  /// +9.81 along the site's up axis at rest).
  Eigen::Vector3d specific_force{Eigen::Vector3d::Zero()};
};

/// Reads the sensors imu_mjcf() declared from mjData's sensordata. The values are those of the
/// last mj_forward or mj_step (mj_step: the state at the start of that step).
class ImuTruthReader {
 public:
  /// Throws std::invalid_argument naming the sensor if the model lacks NAME_gyro or NAME_accel
  /// (or they are not a gyro and an accelerometer).
  ImuTruthReader(const mjModel_* m, const std::string& sensor_name);
  [[nodiscard]] ImuTruth read(const mjData_* d) const;

 private:
  int gyro_adr_{-1};
  int accel_adr_{-1};
};

}  // namespace concert::sim
