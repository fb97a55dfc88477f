#include "concert/sim/ray_sensors.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace concert::sim {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Culling slack in units of a column or ring step: culling must never drop a ray that hits.
constexpr double kIndexSlack = 1e-6;

// Messages are literals: checks on the per-reading paths must not allocate.
void require(bool ok, const char* what) {
  if (!ok) {
    throw std::invalid_argument(what);
  }
}

/// Whether ray sensors see geom `g`: group kWorldGeomGroup and visible. mj_ray's rule, so the
/// reference and the fast path agree: a geom whose rgba (or material) alpha is 0 is invisible to
/// rays; unlike mj_ray, planes and height fields of other groups are not seen either.
bool seen(const mjModel* m, int g) {
  if (m->geom_group[g] != kWorldGeomGroup) {
    return false;
  }
  const int mat = m->geom_matid[g];
  const float alpha = mat >= 0 ? m->mat_rgba[4 * mat + 3] : m->geom_rgba[4 * g + 3];
  return alpha != 0.0f;
}

/// Rays from a sensor's origin against one geom, directions in the sensor frame. Planes and boxes
/// (the floor and most walls and obstacles) are intersected here, in the geom's frame with the
/// sensor's origin and the geom-from-sensor rotation computed once: MuJoCo's ray_plane / ray_box
/// rules (front face of a plane only, within its size if given; a box's nearest face crossing at
/// x >= 0, its exit face from inside), 3-4x cheaper than mju_rayGeom, which transforms both the
/// point and the direction and tests a bounding sphere per call. Other types go to MuJoCo's own
/// routine (mju_rayGeom, mj_rayMesh, mj_rayHfield) with the world direction.
class GeomRay {
 public:
  GeomRay(const mjModel* m, const mjData* d, int g, const Eigen::Isometry3d& world_T_sensor)
      : m_(m),
        d_(d),
        g_(g),
        type_(m->geom_type[g]),
        world_R_sensor_(world_T_sensor.linear()),
        origin_(world_T_sensor.translation()) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> world_R_geom(d->geom_xmat +
                                                                                      9 * g);
    const Eigen::Map<const Eigen::Vector3d> geom_pos(d->geom_xpos + 3 * g);
    geom_R_sensor_ = world_R_geom.transpose() * world_R_sensor_;
    origin_in_geom_ = world_R_geom.transpose() * (origin_ - geom_pos);
    size_ = Eigen::Map<const Eigen::Vector3d>(m->geom_size + 3 * g);
    centre_in_sensor_ = world_R_sensor_.transpose() * (geom_pos - origin_);
  }

  /// Distance along the unit direction `dir` (sensor frame) to the geom, or -1.
  [[nodiscard]] double operator()(const Eigen::Vector3d& dir) const {
    switch (type_) {
      case mjGEOM_PLANE:
        return plane(geom_R_sensor_ * dir);
      case mjGEOM_BOX:
        return box(geom_R_sensor_ * dir);
      default: {
        const Eigen::Vector3d world_dir = world_R_sensor_ * dir;
        if (type_ == mjGEOM_MESH) {
          return mj_rayMesh(m_, d_, g_, origin_.data(), world_dir.data());
        }
        if (type_ == mjGEOM_HFIELD) {
          return mj_rayHfield(m_, d_, g_, origin_.data(), world_dir.data());
        }
        return mju_rayGeom(d_->geom_xpos + 3 * g_, d_->geom_xmat + 9 * g_, m_->geom_size + 3 * g_,
                           origin_.data(), world_dir.data(), type_);
      }
    }
  }

  /// The geom's bounding sphere in the sensor frame; unbounded for planes (MuJoCo's rbound 0).
  [[nodiscard]] const Eigen::Vector3d& centre() const { return centre_in_sensor_; }
  [[nodiscard]] double radius() const { return m_->geom_rbound[g_]; }
  [[nodiscard]] bool unbounded() const { return type_ == mjGEOM_PLANE || radius() <= 0.0; }

 private:
  [[nodiscard]] double plane(const Eigen::Vector3d& v) const {
    const Eigen::Vector3d& p = origin_in_geom_;
    if (v.z() > -mjMINVAL) {
      return -1.0;
    }
    const double x = -p.z() / v.z();
    if (x < 0.0) {
      return -1.0;
    }
    const bool inside_x = size_.x() <= 0.0 || std::abs(p.x() + x * v.x()) <= size_.x();
    const bool inside_y = size_.y() <= 0.0 || std::abs(p.y() + x * v.y()) <= size_.y();
    return inside_x && inside_y ? x : -1.0;
  }

  [[nodiscard]] double box(const Eigen::Vector3d& v) const {
    const Eigen::Vector3d& p = origin_in_geom_;
    double best = -1.0;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(v[i]) <= mjMINVAL) {
        continue;
      }
      const int j = (i + 1) % 3;
      const int k = (i + 2) % 3;
      for (const double side : {-1.0, 1.0}) {
        const double x = (side * size_[i] - p[i]) / v[i];
        if (x >= 0.0 && (best < 0.0 || x < best) && std::abs(p[j] + x * v[j]) <= size_[j] &&
            std::abs(p[k] + x * v[k]) <= size_[k]) {
          best = x;
        }
      }
    }
    return best;
  }

  const mjModel* m_;
  const mjData* d_;
  int g_;
  int type_;
  Eigen::Matrix3d world_R_sensor_;
  Eigen::Vector3d origin_;
  Eigen::Matrix3d geom_R_sensor_;
  Eigen::Vector3d origin_in_geom_;
  Eigen::Vector3d size_;
  Eigen::Vector3d centre_in_sensor_;
};

/// Index range [lo, hi] of the evenly spaced values first + i * step (i in [0, count)) that can
/// lie in [from, to], widened by kIndexSlack; lo > hi when none.
std::pair<long, long> index_range(double from, double to, double first, double step) {
  return {static_cast<long>(std::ceil((from - first) / step - kIndexSlack)),
          static_cast<long>(std::floor((to - first) / step + kIndexSlack))};
}

}  // namespace

// ----------------------------------------------------------------------------------------------
// Lidar

LidarSimulator::LidarSimulator(const LidarParams& params) : params_(params) {
  require(params.rings >= 1, "LidarParams.rings must be at least 1");
  require(params.columns >= 1, "LidarParams.columns must be at least 1");
  require(std::isfinite(params.elevation_min) && std::isfinite(params.elevation_max) &&
              params.elevation_min <= params.elevation_max,
          "LidarParams: elevation_min must not exceed elevation_max");
  require(params.elevation_min > -kPi / 2 && params.elevation_max < kPi / 2,
          "LidarParams: elevations must lie within (-90°, 90°)");
  require(params.range_min >= 0.0 && params.range_max > params.range_min &&
              std::isfinite(params.range_max),
          "LidarParams: need 0 <= range_min < range_max < inf");
  require(params.range_noise >= 0.0 && std::isfinite(params.range_noise),
          "LidarParams.range_noise must be >= 0");
  const double step =
      params.rings > 1 ? (params.elevation_max - params.elevation_min) / (params.rings - 1) : 0.0;
  for (std::uint32_t r = 0; r < params.rings; ++r) {
    const double e = params.elevation_min + r * step;
    elevations_.push_back(static_cast<float>(e));
    ring_cos_.push_back(std::cos(e));
    ring_sin_.push_back(std::sin(e));
  }
  const double inc = 2.0 * kPi / params.columns;
  for (std::uint32_t c = 0; c < params.columns; ++c) {
    column_cos_.push_back(std::cos(-kPi + c * inc));
    column_sin_.push_back(std::sin(-kPi + c * inc));
  }
}

void LidarSimulator::fill_header(hardware::LidarScan& out) const {
  out.elevations.assign(elevations_.begin(), elevations_.end());
  out.azimuth_min = -kPi;
  out.azimuth_increment = 2.0 * kPi / params_.columns;
  out.columns = params_.columns;
  out.range_min = static_cast<float>(params_.range_min);
  out.range_max = static_cast<float>(params_.range_max);
}

void LidarSimulator::scan(const mjModel_* model, const mjData_* data,
                          const Eigen::Isometry3d& world_T_sensor, std::mt19937_64& rng,
                          hardware::LidarScan& out) const {
  const mjModel* m = model;
  const mjData* d = data;
  const long rings = params_.rings;
  const long columns = params_.columns;
  fill_header(out);
  // out.ranges holds the nearest hit distance [m] (+inf: none) until the final pass.
  out.ranges.assign(static_cast<std::size_t>(rings * columns),
                    std::numeric_limits<float>::infinity());
  float* best = out.ranges.data();

  const double column_step = 2.0 * kPi / static_cast<double>(columns);
  const double ring_step =
      rings > 1 ? (params_.elevation_max - params_.elevation_min) / static_cast<double>(rings - 1)
                : 1.0;

  for (int g = 0; g < m->ngeom; ++g) {
    if (!seen(m, g)) {
      continue;
    }
    // Which rays can meet the geom's bounding sphere: columns whose vertical half-plane meets it
    // (exact for the sphere), rings within its elevation band (conservative: the angle between
    // two directions is at least the difference of their elevations).
    const GeomRay ray(m, d, g, world_T_sensor);
    const Eigen::Vector3d& centre = ray.centre();
    const double radius = ray.radius();
    long c_lo = 0;
    long c_hi = columns - 1;
    long r_lo = 0;
    long r_hi = rings - 1;
    const double dist = centre.norm();
    if (!ray.unbounded() && dist > radius) {
      if (dist - radius > params_.range_max) {
        continue;
      }
      const double rho = std::hypot(centre.x(), centre.y());
      if (rho > radius) {
        const double azimuth = std::atan2(centre.y(), centre.x());
        const double half = std::asin(radius / rho);
        std::tie(c_lo, c_hi) = index_range(azimuth - half, azimuth + half, -kPi, column_step);
        if (c_hi - c_lo + 1 >= columns) {
          c_lo = 0;
          c_hi = columns - 1;
        }
      }
      const double elevation = std::atan2(centre.z(), rho);
      const double half = std::asin(radius / dist);
      const auto [lo, hi] =
          index_range(elevation - half, elevation + half, params_.elevation_min, ring_step);
      r_lo = std::max(lo, 0L);
      r_hi = std::min(hi, rings - 1);
      if (rings == 1) {  // index_range's step is a stand-in: test the one ring's elevation itself
        r_lo = 0;
        r_hi = std::abs(params_.elevation_min - elevation) <= half ? 0 : -1;
      }
    }
    for (long k = c_lo; k <= c_hi; ++k) {
      const long c = ((k % columns) + columns) % columns;
      for (long r = r_lo; r <= r_hi; ++r) {
        const Eigen::Vector3d dir(ring_cos_[r] * column_cos_[c], ring_cos_[r] * column_sin_[c],
                                  ring_sin_[r]);
        const double t = ray(dir);
        float& b = best[r * columns + c];
        if (t >= 0.0 && t < b) {
          b = static_cast<float>(t);
        }
      }
    }
  }

  std::normal_distribution<double> noise(0.0, params_.range_noise);
  const bool noisy = params_.noise && params_.range_noise > 0.0;
  for (float& r : out.ranges) {
    if (!std::isfinite(r)) {
      r = 0.0f;
      continue;
    }
    const double measured = noisy ? r + noise(rng) : r;
    r = measured >= params_.range_min && measured <= params_.range_max
            ? static_cast<float>(measured)
            : 0.0f;
  }
}

void LidarSimulator::scan_reference(const mjModel_* model, const mjData_* data,
                                    const Eigen::Isometry3d& world_T_sensor,
                                    hardware::LidarScan& out) const {
  const mjModel* m = model;
  const mjData* d = data;
  fill_header(out);
  out.ranges.assign(static_cast<std::size_t>(params_.rings) * params_.columns, 0.0f);
  mjtByte groups[mjNGROUP] = {};
  groups[kWorldGeomGroup] = 1;
  const Eigen::Matrix3d rot = world_T_sensor.linear();
  for (std::uint32_t r = 0; r < params_.rings; ++r) {
    for (std::uint32_t c = 0; c < params_.columns; ++c) {
      const Eigen::Vector3d dir =
          rot * Eigen::Vector3d(ring_cos_[r] * column_cos_[c], ring_cos_[r] * column_sin_[c],
                                ring_sin_[r]);
      int geom = -1;
      const double t =
          mj_ray(m, d, world_T_sensor.translation().data(), dir.data(), groups, 1, -1, &geom);
      if (t >= params_.range_min && t <= params_.range_max) {
        out.ranges[r * params_.columns + c] = static_cast<float>(t);
      }
    }
  }
}

// ----------------------------------------------------------------------------------------------
// Planar scan

void derive_scan2d(const Scan2dParams& params, std::span<const PosedLidarScan> scans,
                   const Eigen::Isometry3d& world_T_base, double floor_height,
                   std::string_view base_frame, hardware::LaserScan2d& out) {
  require(params.bins >= 1, "Scan2dParams.bins must be at least 1");
  const double inc = 2.0 * kPi / params.bins;
  out.frame.assign(base_frame);
  out.angle_min = -kPi;
  out.angle_increment = inc;
  out.range_min = 0.0f;
  out.range_max = static_cast<float>(params.range_max);
  out.ranges.assign(params.bins, std::numeric_limits<float>::infinity());
  out.stamp = 0.0;
  const Eigen::Isometry3d base_T_world = world_T_base.inverse();
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (scans[i].scan == nullptr) {
      throw std::invalid_argument("derive_scan2d: scan " + std::to_string(i) + " is null");
    }
    const hardware::LidarScan& scan = *scans[i].scan;
    if (scan.ranges.size() != scan.elevations.size() * scan.columns) {
      throw std::invalid_argument("derive_scan2d: lidar scan '" + scan.sensor + "' has " +
                                  std::to_string(scan.ranges.size()) + " ranges for " +
                                  std::to_string(scan.elevations.size()) + " rings x " +
                                  std::to_string(scan.columns) + " columns");
    }
    out.stamp = i == 0 ? scan.stamp : std::max(out.stamp, scan.stamp);
    const Eigen::Isometry3d& world_T_sensor = scans[i].world_T_sensor;
    const Eigen::Isometry3d base_T_sensor = base_T_world * world_T_sensor;
    // Height above the floor needs only the world z row of the sensor pose.
    const Eigen::Vector3d world_z_row = world_T_sensor.linear().row(2).transpose();
    const double sensor_height = world_T_sensor.translation().z() - floor_height;
    // Rings outer (their trigonometry once), columns inner with the azimuth's cosine and sine
    // advanced by a rotation (exact to ~1e-13 over a revolution).
    const double step_cos = std::cos(scan.azimuth_increment);
    const double step_sin = std::sin(scan.azimuth_increment);
    for (std::size_t r = 0; r < scan.elevations.size(); ++r) {
      const double ce = std::cos(static_cast<double>(scan.elevations[r]));
      const double se = std::sin(static_cast<double>(scan.elevations[r]));
      double ca = std::cos(scan.azimuth_min);
      double sa = std::sin(scan.azimuth_min);
      const float* ranges = scan.ranges.data() + r * scan.columns;
      for (std::uint32_t c = 0; c < scan.columns; ++c) {
        const double range = ranges[c];
        const Eigen::Vector3d p(range * ce * ca, range * ce * sa, range * se);
        const double next_ca = ca * step_cos - sa * step_sin;
        sa = sa * step_cos + ca * step_sin;
        ca = next_ca;
        if (!(range > 0.0)) {
          continue;
        }
        const double height = sensor_height + world_z_row.dot(p);
        if (height < params.height_min || height > params.height_max) {
          continue;
        }
        const Eigen::Vector3d q = base_T_sensor * p;
        const double planar = std::sqrt(q.x() * q.x() + q.y() * q.y());
        if (planar > params.range_max) {
          continue;
        }
        auto bin = static_cast<long>(std::floor((std::atan2(q.y(), q.x()) + kPi) / inc));
        // atan2 = π lands on the last bin
        bin = std::clamp(bin, 0L, static_cast<long>(params.bins) - 1);
        float& b = out.ranges[static_cast<std::size_t>(bin)];
        b = std::min(b, static_cast<float>(planar));
      }
    }
  }
}

// ----------------------------------------------------------------------------------------------
// Sonar

SonarSimulator::SonarSimulator(const SonarParams& params) : params_(params) {
  require(params.rays >= 1, "SonarParams.rays must be at least 1");
  require(params.range_min >= 0.0 && params.range_max > params.range_min &&
              std::isfinite(params.range_max),
          "SonarParams: need 0 <= range_min < range_max < inf");
  require(params.field_of_view > 0.0 && params.field_of_view < kPi,
          "SonarParams.field_of_view must lie in (0, π)");
  require(params.range_noise >= 0.0 && std::isfinite(params.range_noise),
          "SonarParams.range_noise must be >= 0");
  directions_.emplace_back(Eigen::Vector3d::UnitX());
  const int off_axis = static_cast<int>(params.rays) - 1;
  if (off_axis == 0) {
    return;
  }
  const int rings = std::max(1, static_cast<int>(std::lround(std::sqrt(off_axis / 3.0))));
  const int weights = rings * (rings + 1) / 2;
  int used = 0;
  for (int k = 1; k <= rings; ++k) {
    const int n = k == rings ? off_axis - used
                             : std::max(1, static_cast<int>(std::lround(
                                               static_cast<double>(off_axis * k) / weights)));
    used += n;
    const double h = static_cast<double>(k) / rings * params.field_of_view / 2.0;
    for (int j = 0; j < n; ++j) {
      const double phi = 2.0 * kPi * j / n;
      directions_.emplace_back(std::cos(h), std::sin(h) * std::cos(phi),
                               std::sin(h) * std::sin(phi));
    }
  }
}

float SonarSimulator::range(const mjModel_* model, const mjData_* data,
                            const Eigen::Isometry3d& world_T_sensor, std::mt19937_64& rng) const {
  const mjModel* m = model;
  const mjData* d = data;
  const double half_fov = params_.field_of_view / 2.0;
  double nearest = kInf;
  for (int g = 0; g < m->ngeom; ++g) {
    if (!seen(m, g)) {
      continue;
    }
    // Cull geoms whose bounding sphere is out of reach or outside the cone.
    const GeomRay ray(m, d, g, world_T_sensor);
    const double dist = ray.centre().norm();
    if (!ray.unbounded() && dist > ray.radius()) {
      if (dist - ray.radius() > std::min(params_.range_max, nearest)) {
        continue;
      }
      const double off_axis = std::acos(std::clamp(ray.centre().x() / dist, -1.0, 1.0));
      if (off_axis > half_fov + std::asin(ray.radius() / dist)) {
        continue;
      }
    }
    for (const Eigen::Vector3d& dir : directions_) {
      const double t = ray(dir);
      if (t >= 0.0 && t < nearest) {
        nearest = t;
      }
    }
  }
  if (nearest > params_.range_max) {
    return std::numeric_limits<float>::infinity();
  }
  if (params_.noise && params_.range_noise > 0.0) {
    nearest += std::normal_distribution<double>(0.0, params_.range_noise)(rng);
  }
  return static_cast<float>(std::clamp(nearest, params_.range_min, params_.range_max));
}

void SonarSimulator::read(const mjModel_* m, const mjData_* d,
                          const Eigen::Isometry3d& world_T_sensor, std::mt19937_64& rng,
                          hardware::SonarRange& out) const {
  out.range = range(m, d, world_T_sensor, rng);
  out.range_min = static_cast<float>(params_.range_min);
  out.range_max = static_cast<float>(params_.range_max);
  out.field_of_view = static_cast<float>(params_.field_of_view);
}

}  // namespace concert::sim
