#pragma once
// Simulated ray sensors against a MuJoCo scene: multi-beam lidars (Velodyne VLP-16), the planar
// scan navigation derives from them, and ultrasound range sensors. They see MuJoCo geom group
// kWorldGeomGroup only (geom_groups.hpp): the robot's own geoms are invisible to them, as a real
// robot filters its self-hits. Frames as in hardware/sensors.hpp: x is the beam/cone axis at
// azimuth 0, lidar rings are at elevations about the frame's xy plane.
//
// The simulators are immutable after construction; every call reads the model and the data
// (geom poses of the last mj_forward / mj_step: mjData's geom_xpos, geom_xmat) and writes only
// its output and the caller's random generator, so any number of threads may use one simulator
// with their own mjData and generator.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <span>
#include <string_view>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "concert/sim/geom_groups.hpp"
#include "concert/sim/sensor_params.hpp"

struct mjModel_;
struct mjData_;

namespace concert::sim {

/// A rotating multi-beam lidar: one revolution taken at one instant.
///
/// Beams: `rings` elevations evenly spaced from elevation_min to elevation_max (one ring: at
/// elevation_min), `columns` azimuths from -π in steps of 2π / columns, about the sensor frame's z
/// axis from its x axis. Ray (ring r, column c) has the direction (cos e cos a, cos e sin a, sin e)
/// in the sensor frame.
///
/// Cost (14,400 rays per revolution at 10 Hz, two lidars, on cores shared with the 1 kHz physics
/// loop): the rays are not cast one by one through mj_ray, which tests every geom of the model
/// for every ray (the robot's geoms included, only to reject them by group). Once per scan each
/// world geom's bounding sphere is projected into the sensor frame and gives the columns whose
/// vertical half-plane it meets and the rings within its elevation band; only those rays are
/// intersected with that geom. Planes and boxes (the floor, walls, most obstacles) are
/// intersected in the geom's frame with MuJoCo's rules (see ray_sensors.cpp); every other type
/// by MuJoCo's own routine (mju_rayGeom, mj_rayMesh, mj_rayHfield), so meshes and height fields
/// are exact too. Planes (infinite) are tested by every ray. The result equals mj_ray with
/// geomgroup = {group 0} to float rounding (tested on every geom type); on the platform scene of
/// bench_ray_sensors it costs about a third of per-ray mj_ray (scan_reference).
///
/// A world geom whose rgba (or material) alpha is 0 is invisible to the rays, as to mj_ray.
class LidarSimulator {
 public:
  /// Throws std::invalid_argument naming the parameter if `params` cannot describe a lidar
  /// (no rings or columns, range_max <= range_min, elevations outside (-90°, 90°), ...).
  explicit LidarSimulator(const LidarParams& params);

  /// One revolution from the sensor pose `world_T_sensor` (sensor frame in MuJoCo's world frame).
  /// Fills out.elevations, azimuth_min, azimuth_increment, columns, ranges, range_min and
  /// range_max; sensor, frame and stamp are the caller's. A range is the distance to the nearest
  /// world surface plus zero-mean Gaussian noise of std-dev range_noise (when params.noise); a
  /// measured range outside [range_min, range_max] (or no surface) reads 0 (no return). Does not
  /// allocate once `out` and the calling thread's scratch have their size (after the first call).
  void scan(const mjModel_* m, const mjData_* d, const Eigen::Isometry3d& world_T_sensor,
            std::mt19937_64& rng, hardware::LidarScan& out) const;

  /// The same scan with one mj_ray call per ray (geom group 0 only) and no noise: the reference
  /// the fast path is tested and benchmarked against.
  void scan_reference(const mjModel_* m, const mjData_* d, const Eigen::Isometry3d& world_T_sensor,
                      hardware::LidarScan& out) const;

  [[nodiscard]] const LidarParams& params() const { return params_; }
  /// [rad] elevation of each ring.
  [[nodiscard]] const std::vector<float>& elevations() const { return elevations_; }

 private:
  void fill_header(hardware::LidarScan& out) const;

  LidarParams params_;
  std::vector<float> elevations_;
  std::vector<double> ring_cos_, ring_sin_;      // per ring
  std::vector<double> column_cos_, column_sin_;  // per column
};

/// One lidar scan and where it was taken from (MuJoCo's world frame).
struct PosedLidarScan {
  const hardware::LidarScan* scan{nullptr};
  Eigen::Isometry3d world_T_sensor{Eigen::Isometry3d::Identity()};
};

/// The planar scan navigation reads, from any number of lidar scans. Every return (range > 0) is
/// placed in the world with its scan's pose; it is kept if its height above the floor,
/// z_world - floor_height, lies in [params.height_min, params.height_max]; it is then expressed
/// in the robot's root-link frame (`world_T_base`) and projected onto that frame's xy plane:
/// bearing atan2(y, x), range hypot(x, y). Bins: params.bins over 360° from angle_min = -π
/// (bin i covers [-π + i·inc, -π + (i + 1)·inc)); each bin reads its nearest planar range, +inf
/// if it has none within params.range_max. out.frame = base_frame; out.stamp = the newest scan's
/// stamp; out.range_min = 0 (a planar range can be arbitrarily short), out.range_max =
/// params.range_max. Does not allocate once out.ranges has its size. Throws std::invalid_argument
/// if params.bins is 0 or a scan pointer is null.
void derive_scan2d(const Scan2dParams& params, std::span<const PosedLidarScan> scans,
                   const Eigen::Isometry3d& world_T_base, double floor_height,
                   std::string_view base_frame, hardware::LaserScan2d& out);

/// An ultrasound range sensor: the nearest echo within its cone.
///
/// Rays: the cone's axis (the sensor frame's x axis) plus K rings at half-angles
/// (k / K)·field_of_view / 2, k = 1..K, the outermost on the cone's edge; ring k has a number of
/// rays proportional to k (even density over the cone's face), the first at the frame's +y side:
/// direction (cos h, sin h cos φ, sin h sin φ), φ = 2π j / n_k. K = round(√((rays - 1) / 3))
/// (at least 1): 25 rays are the axis + 4 + 8 + 12.
class SonarSimulator {
 public:
  /// Throws std::invalid_argument naming the parameter (no rays, range_max <= range_min, field of
  /// view outside (0, π), negative noise).
  explicit SonarSimulator(const SonarParams& params);

  /// [m] The nearest world surface along the rays within range_max, plus zero-mean Gaussian noise
  /// of std-dev range_noise (when params.noise), clamped to [range_min, range_max]: an echo nearer
  /// than range_min reads range_min (the transducer is still ringing: the sensor saturates).
  /// +inf when no surface is within range_max.
  [[nodiscard]] float range(const mjModel_* m, const mjData_* d,
                            const Eigen::Isometry3d& world_T_sensor, std::mt19937_64& rng) const;

  /// A SonarRange with range() and the sensor's parameters (sensor and frame left empty).
  void read(const mjModel_* m, const mjData_* d, const Eigen::Isometry3d& world_T_sensor,
            std::mt19937_64& rng, hardware::SonarRange& out) const;

  [[nodiscard]] const SonarParams& params() const { return params_; }
  /// Unit ray directions in the sensor frame (axis first).
  [[nodiscard]] const std::vector<Eigen::Vector3d>& directions() const { return directions_; }

 private:
  SonarParams params_;
  std::vector<Eigen::Vector3d> directions_;
};

}  // namespace concert::sim
