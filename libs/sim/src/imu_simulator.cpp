#include "concert/sim/imu_simulator.hpp"

#include <mujoco/mujoco.h>

#include <cmath>
#include <stdexcept>

#include "mjcf_text.hpp"

namespace concert::sim {

namespace {

void require(bool ok, const std::string& what) {  // construction only: may allocate
  if (!ok) {
    throw std::invalid_argument(what);
  }
}

bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

ImuSimulator::ImuSimulator(const ImuParams& params, std::uint64_t seed)
    : params_(params), rng_(seed) {
  require(std::isfinite(params.rate) && params.rate > 0.0, "ImuParams.rate must be > 0");
  require(non_negative(params.gyro_noise_density) && non_negative(params.accel_noise_density),
          "ImuParams: noise densities must be >= 0");
  require(non_negative(params.gyro_bias_sigma) && non_negative(params.accel_bias_sigma),
          "ImuParams: bias sigmas must be >= 0");
  require(non_negative(params.gyro_bias_walk) && non_negative(params.accel_bias_walk),
          "ImuParams: bias random walks must be >= 0");
  if (params.noise) {
    gyro_sigma_ = params.gyro_noise_density * std::sqrt(params.rate);
    accel_sigma_ = params.accel_noise_density * std::sqrt(params.rate);
    gyro_bias_ = gaussian(params.gyro_bias_sigma);
    accel_bias_ = gaussian(params.accel_bias_sigma);
  }
}

Eigen::Vector3d ImuSimulator::gaussian(double sigma) {
  const double x = normal_(rng_);
  const double y = normal_(rng_);
  const double z = normal_(rng_);
  return sigma * Eigen::Vector3d(x, y, z);
}

void ImuSimulator::sample(const Eigen::Vector3d& true_angular_velocity,
                          const Eigen::Vector3d& true_specific_force, double dt,
                          hardware::ImuSample& out) {
  if (!non_negative(dt)) {
    throw std::invalid_argument("ImuSimulator::sample: dt must be finite and >= 0, got " +
                                std::to_string(dt));
  }
  out.angular_velocity = true_angular_velocity;
  out.linear_acceleration = true_specific_force;
  out.angular_velocity_variance = gyro_sigma_ * gyro_sigma_;
  out.linear_acceleration_variance = accel_sigma_ * accel_sigma_;
  if (!params_.noise) {
    return;
  }
  const double root_dt = std::sqrt(dt);
  gyro_bias_ += gaussian(params_.gyro_bias_walk * root_dt);
  accel_bias_ += gaussian(params_.accel_bias_walk * root_dt);
  out.angular_velocity += gyro_bias_ + gaussian(gyro_sigma_);
  out.linear_acceleration += accel_bias_ + gaussian(accel_sigma_);
}

ImuMjcf imu_mjcf(const std::string& sensor_name, const Eigen::Isometry3d& body_T_imu) {
  const Eigen::Vector3d p = body_T_imu.translation();
  const Eigen::Quaterniond q(body_T_imu.linear());
  ImuMjcf out;
  out.site = "<site name=\"" + sensor_name + "\" pos=\"" + mjcf::vec(p.x(), p.y(), p.z()) +
             "\" quat=\"" + mjcf::num(q.w()) + " " + mjcf::vec(q.x(), q.y(), q.z()) + "\"/>\n";
  out.sensors = "<gyro name=\"" + sensor_name + "_gyro\" site=\"" + sensor_name +
                "\"/>\n<accelerometer name=\"" + sensor_name + "_accel\" site=\"" + sensor_name +
                "\"/>\n";
  return out;
}

ImuTruthReader::ImuTruthReader(const mjModel_* model, const std::string& sensor_name) {
  const mjModel* m = model;
  auto address = [&](const std::string& name, int type, const char* what) {
    const int id = mj_name2id(m, mjOBJ_SENSOR, name.c_str());
    require(id >= 0, "IMU '" + sensor_name + "': the MuJoCo model has no sensor '" + name +
                         "' (see imu_mjcf)");
    require(m->sensor_type[id] == type && m->sensor_dim[id] == 3,
            "IMU '" + sensor_name + "': MuJoCo sensor '" + name + "' is not " + what);
    return m->sensor_adr[id];
  };
  gyro_adr_ = address(sensor_name + "_gyro", mjSENS_GYRO, "a gyro");
  accel_adr_ = address(sensor_name + "_accel", mjSENS_ACCELEROMETER, "an accelerometer");
}

ImuTruth ImuTruthReader::read(const mjData_* data) const {
  const mjData* d = data;
  ImuTruth t;
  t.angular_velocity = Eigen::Map<const Eigen::Vector3d>(d->sensordata + gyro_adr_);
  t.specific_force = Eigen::Map<const Eigen::Vector3d>(d->sensordata + accel_adr_);
  return t;
}

}  // namespace concert::sim
