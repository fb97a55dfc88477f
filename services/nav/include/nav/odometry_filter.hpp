#pragma once
// Odometry filter (paper section 5.3, "filtering"): an extended Kalman filter fusing the wheel
// odometry twist of the robot service with the IMU's yaw rate, whose bias it estimates. Plain
// C++/Eigen; no DDS.
//
// State (7): pose (x, y, yaw) of the base in the odometry frame [m, m, rad], twist (vx, vy, wz)
// in the base frame [m/s, m/s, rad/s], gyro bias b [rad/s]. Process model: constant twist
// driven by white acceleration noise, the pose integrated from the twist, the bias a random
// walk. Measurements: the wheel twist (vx, vy, wz) with its 3x3 covariance, and the gyro's yaw
// rate = wz + b with its variance. The wheels make the bias observable (at rest and whenever
// they do not slip); the gyro carries the heading through the turns where the wheels skid.

#include <Eigen/Core>
#include <stdexcept>

namespace concert::nav {

/// A measurement the filter refuses (NaN, negative variance, a time before the filter's); what()
/// names the measurement and the field. The filter's state is unchanged.
class OdometryFilterError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A well-formed measurement that came too late (its time more than max_lag before the
/// filter's): dropped, not bad input. A loaded host delivers a sample late now and then; the
/// caller counts these apart from refused input.
class LateMeasurement : public OdometryFilterError {
 public:
  using OdometryFilterError::OdometryFilterError;
};

/// Noise model and options of the filter.
struct OdometryFilterParams {
  double linear_accel_noise{0.5};        ///< white acceleration on vx, vy [m/s^2/sqrt(Hz)]
  double angular_accel_noise{0.5};       ///< white angular acceleration on wz [rad/s^2/sqrt(Hz)]
  double gyro_bias_walk{1e-4};           ///< bias random walk [rad/s^2/sqrt(Hz)]
  double initial_gyro_bias_sigma{0.02};  ///< [rad/s]
  double initial_twist_sigma{0.1};       ///< [m/s] and [rad/s]
  /// A measurement up to this much older than the filter's time is applied at the filter's
  /// time (sensors interleave with jitter); an older one is refused [s].
  double max_lag{0.05};
  double max_step{0.02};  ///< longest single prediction step; longer gaps are sub-stepped [s]
};

/// Wheel odometry: the base twist the robot service computes from the legs.
struct WheelTwist {
  double stamp{0.0};                               ///< [s]
  Eigen::Vector3d twist{Eigen::Vector3d::Zero()};  ///< vx, vy [m/s], wz [rad/s], base frame
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Identity()};  ///< of twist [(m/s)^2, (rad/s)^2]
};

/// The IMU's angular rate about the base frame's z axis (rotate the IMU's angular velocity by
/// base_T_imu first).
struct GyroRate {
  double stamp{0.0};      ///< [s]
  double yaw_rate{0.0};   ///< [rad/s], bias included
  double variance{1e-5};  ///< of the white noise [(rad/s)^2]
};

/// The filter's estimate.
struct FilteredOdometry {
  double stamp{0.0};                               ///< [s]
  Eigen::Vector3d pose{Eigen::Vector3d::Zero()};   ///< x, y [m], yaw [rad] in (-pi, pi], odom frame
  Eigen::Vector3d twist{Eigen::Vector3d::Zero()};  ///< vx, vy [m/s], wz [rad/s], base frame
  Eigen::Matrix3d pose_covariance{Eigen::Matrix3d::Zero()};   ///< of pose
  Eigen::Matrix3d twist_covariance{Eigen::Matrix3d::Zero()};  ///< of twist
  double gyro_bias{0.0};                                      ///< [rad/s]
  double gyro_bias_sigma{0.0};                                ///< [rad/s]
};

/// The EKF. Not thread-safe: one owner feeds it.
class OdometryFilter {
 public:
  /// Throws OdometryFilterError naming a parameter that is not finite and positive.
  explicit OdometryFilter(const OdometryFilterParams& params = {});

  /// Restarts at `pose` (x, y [m], yaw [rad]) at time `stamp` [s], at rest, with zero pose
  /// covariance and the initial bias uncertainty. Until the first reset or measurement the
  /// filter starts at the origin at the first measurement's time.
  void reset(double stamp, const Eigen::Vector3d& pose = Eigen::Vector3d::Zero());

  /// Predicts to `stamp` [s] without a measurement (the covariance grows). Throws
  /// OdometryFilterError for a time that is not finite, LateMeasurement for one more than max_lag before the
  /// filter's.
  void predict(double stamp);
  /// Predicts to the measurement's time and fuses it. Throws OdometryFilterError (state kept)
  /// for NaN/inf values or a covariance that is not symmetric with a positive diagonal, and
  /// LateMeasurement (state kept) for a time more than max_lag before the filter's.
  void update(const WheelTwist& wheels);
  /// Same for a gyro sample (variance must be positive).
  void update(const GyroRate& gyro);

  /// The current estimate.
  [[nodiscard]] FilteredOdometry estimate() const;
  [[nodiscard]] const OdometryFilterParams& params() const { return params_; }

 private:
  using State = Eigen::Matrix<double, 7, 1>;
  using Covariance = Eigen::Matrix<double, 7, 7>;

  void check_time(double stamp, const char* what) const;
  void advance(double stamp);
  template <int M>
  void correct(const Eigen::Matrix<double, M, 1>& innovation, const Eigen::Matrix<double, M, 7>& h,
               const Eigen::Matrix<double, M, M>& r);

  OdometryFilterParams params_;
  bool started_{false};
  double stamp_{0.0};
  State x_{State::Zero()};
  Covariance p_{Covariance::Zero()};
};

}  // namespace concert::nav
