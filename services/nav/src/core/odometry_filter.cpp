#include "nav/odometry_filter.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <string>

namespace concert::nav {

namespace {

constexpr int kYaw = 2;
constexpr int kVx = 3;
constexpr int kWz = 5;
constexpr int kBias = 6;

double wrap(double angle) {
  angle = std::remainder(angle, 2.0 * std::numbers::pi);
  return angle <= -std::numbers::pi ? angle + 2.0 * std::numbers::pi : angle;
}

void require_finite(double value, const std::string& what) {
  if (!std::isfinite(value)) {
    throw OdometryFilterError("odometry filter: " + what + " is not finite (" +
                              std::to_string(value) + "); measurement ignored");
  }
}

}  // namespace

OdometryFilter::OdometryFilter(const OdometryFilterParams& params) : params_(params) {
  const std::pair<const char*, double> positive[] = {
      {"linear_accel_noise", params.linear_accel_noise},
      {"angular_accel_noise", params.angular_accel_noise},
      {"gyro_bias_walk", params.gyro_bias_walk},
      {"initial_gyro_bias_sigma", params.initial_gyro_bias_sigma},
      {"initial_twist_sigma", params.initial_twist_sigma},
      {"max_lag", params.max_lag},
      {"max_step", params.max_step}};
  for (const auto& [name, value] : positive) {
    if (!std::isfinite(value) || value <= 0.0) {
      throw OdometryFilterError(std::string("odometry filter parameter ") + name +
                                " must be finite and positive, got " + std::to_string(value));
    }
  }
}

void OdometryFilter::reset(double stamp, const Eigen::Vector3d& pose) {
  require_finite(stamp, "reset stamp");
  for (int i = 0; i < 3; ++i) require_finite(pose[i], "reset pose[" + std::to_string(i) + "]");
  started_ = true;
  stamp_ = stamp;
  x_ = State::Zero();
  x_.head<3>() = pose;
  x_[kYaw] = wrap(pose[kYaw]);
  p_ = Covariance::Zero();
  const double t = params_.initial_twist_sigma * params_.initial_twist_sigma;
  p_.block<3, 3>(kVx, kVx) = Eigen::Matrix3d::Identity() * t;
  p_(kBias, kBias) = params_.initial_gyro_bias_sigma * params_.initial_gyro_bias_sigma;
}

void OdometryFilter::check_time(double stamp, const char* what) const {
  require_finite(stamp, std::string(what) + " stamp");
  if (started_ && stamp < stamp_ - params_.max_lag) {
    throw LateMeasurement("odometry filter: " + std::string(what) + " stamp " +
                              std::to_string(stamp) + " s is older than the filter's time " +
                              std::to_string(stamp_) + " s by more than max_lag " +
                              std::to_string(params_.max_lag) + " s; measurement ignored");
  }
}

void OdometryFilter::advance(double stamp) {
  if (!started_) reset(stamp);
  while (stamp > stamp_) {
    const double dt = std::min(stamp - stamp_, params_.max_step);
    const double c = std::cos(x_[kYaw]);
    const double s = std::sin(x_[kYaw]);
    const double vx = x_[kVx];
    const double vy = x_[kVx + 1];
    Covariance f = Covariance::Identity();
    f(0, kYaw) = (-vx * s - vy * c) * dt;
    f(0, kVx) = c * dt;
    f(0, kVx + 1) = -s * dt;
    f(1, kYaw) = (vx * c - vy * s) * dt;
    f(1, kVx) = s * dt;
    f(1, kVx + 1) = c * dt;
    f(kYaw, kWz) = dt;
    x_[0] += (vx * c - vy * s) * dt;
    x_[1] += (vx * s + vy * c) * dt;
    x_[kYaw] = wrap(x_[kYaw] + x_[kWz] * dt);
    Covariance q = Covariance::Zero();
    const double qa = params_.linear_accel_noise * params_.linear_accel_noise * dt;
    q(kVx, kVx) = qa;
    q(kVx + 1, kVx + 1) = qa;
    q(kWz, kWz) = params_.angular_accel_noise * params_.angular_accel_noise * dt;
    q(kBias, kBias) = params_.gyro_bias_walk * params_.gyro_bias_walk * dt;
    p_ = f * p_ * f.transpose() + q;
    stamp_ += dt;
  }
}

void OdometryFilter::predict(double stamp) {
  check_time(stamp, "predict");
  advance(stamp);
}

template <int M>
void OdometryFilter::correct(const Eigen::Matrix<double, M, 1>& innovation,
                             const Eigen::Matrix<double, M, 7>& h,
                             const Eigen::Matrix<double, M, M>& r) {
  const Eigen::Matrix<double, M, M> s = h * p_ * h.transpose() + r;
  const Eigen::Matrix<double, 7, M> k = p_ * h.transpose() * s.inverse();
  x_ += k * innovation;
  x_[kYaw] = wrap(x_[kYaw]);
  const Covariance a = Covariance::Identity() - k * h;
  p_ = a * p_ * a.transpose() + k * r * k.transpose();  // Joseph form: stays symmetric PSD
  p_ = 0.5 * (p_ + p_.transpose());
}

void OdometryFilter::update(const WheelTwist& wheels) {
  check_time(wheels.stamp, "wheel twist");
  for (int i = 0; i < 3; ++i) {
    require_finite(wheels.twist[i], "wheel twist[" + std::to_string(i) + "]");
    for (int j = 0; j < 3; ++j) {
      require_finite(wheels.covariance(i, j),
                     "wheel twist covariance(" + std::to_string(i) + "," + std::to_string(j) + ")");
    }
    if (wheels.covariance(i, i) <= 0.0) {
      throw OdometryFilterError("odometry filter: wheel twist covariance(" + std::to_string(i) +
                                "," + std::to_string(i) +
                                ") = " + std::to_string(wheels.covariance(i, i)) +
                                " is not positive; measurement ignored");
    }
  }
  if (!wheels.covariance.isApprox(wheels.covariance.transpose(), 1e-9)) {
    throw OdometryFilterError(
        "odometry filter: wheel twist covariance is not symmetric; measurement ignored");
  }
  advance(wheels.stamp);
  Eigen::Matrix<double, 3, 7> h = Eigen::Matrix<double, 3, 7>::Zero();
  h.block<3, 3>(0, kVx) = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d innovation = wheels.twist - x_.segment<3>(kVx);
  correct<3>(innovation, h, wheels.covariance);
}

void OdometryFilter::update(const GyroRate& gyro) {
  check_time(gyro.stamp, "gyro");
  require_finite(gyro.yaw_rate, "gyro yaw rate");
  require_finite(gyro.variance, "gyro variance");
  if (gyro.variance <= 0.0) {
    throw OdometryFilterError("odometry filter: gyro variance " + std::to_string(gyro.variance) +
                              " is not positive; measurement ignored");
  }
  advance(gyro.stamp);
  Eigen::Matrix<double, 1, 7> h = Eigen::Matrix<double, 1, 7>::Zero();
  h(0, kWz) = 1.0;
  h(0, kBias) = 1.0;
  Eigen::Matrix<double, 1, 1> innovation;
  innovation << gyro.yaw_rate - x_[kWz] - x_[kBias];
  Eigen::Matrix<double, 1, 1> r;
  r << gyro.variance;
  correct<1>(innovation, h, r);
}

FilteredOdometry OdometryFilter::estimate() const {
  FilteredOdometry out;
  out.stamp = stamp_;
  out.pose = x_.head<3>();
  out.twist = x_.segment<3>(kVx);
  out.pose_covariance = p_.block<3, 3>(0, 0);
  out.twist_covariance = p_.block<3, 3>(kVx, kVx);
  out.gyro_bias = x_[kBias];
  out.gyro_bias_sigma = std::sqrt(p_(kBias, kBias));
  return out;
}

}  // namespace concert::nav
