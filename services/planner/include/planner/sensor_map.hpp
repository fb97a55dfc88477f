#pragma once
// The planner's map from the robot's own sensors (paper section 5.4.1): lidar revolutions and
// depth images (several frames averaged against noise) ray-cast into the Environment's OctoMap
// from the sensor's pose in the map frame. Returns on the robot itself (its collision shapes at
// the current joint state, grown by a padding) never become obstacles, nor do returns from the
// floor (the state checker's floor constraint covers it).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "planner/environment.hpp"
#include "planner/planning_model.hpp"
#include "planner/types.hpp"

namespace concert::planner {

/// What one insert did with its returns.
struct SensorMapStats {
  std::size_t returns = 0;    ///< beams or pixels with a return (range/depth > 0)
  std::size_t occupied = 0;   ///< returns marked occupied (the ray before them free)
  std::size_t self = 0;       ///< returns on the robot's own shapes: dropped (ray not cast)
  std::size_t floor = 0;      ///< returns from the floor band: their ray cleared, nothing marked
  std::size_t cut = 0;        ///< returns beyond sensor_max_range: ray cleared up to it
  std::size_t no_return = 0;  ///< beams or pixels without a return: skipped
};

/// One sensor's returns sorted into rays, ready for Environment::insert_rays.
struct SensorRays {
  RayBundle rays;
  SensorMapStats stats;
};

/// One map update's sensor data, converted by the service: each lidar's newest revolution and
/// each camera's latest depth frames (of the mapper's model version), by sensor name.
struct SensorBatch {
  std::vector<std::pair<std::string, hardware::LidarScan>> scans;
  std::vector<std::pair<std::string, std::vector<hardware::RgbdFrame>>> depth;
};

/// A batch's rays from the sensors' poses, with what each sensor gave.
struct BatchRays {
  std::vector<RayBundle> bundles;    ///< every sensor's rays, to insert with one copy of the map
  SensorMapStats stats;              ///< summed over the sensors used
  std::vector<std::string> used;     ///< "front_lidar", "cam (5 depth frames averaged)"
  std::vector<std::string> refused;  ///< "name: why" (the sensor's data is left out)
};

/// What one map update did, for the service's log line.
struct SensorMapUpdate {
  BatchRays rays;
  double milliseconds = 0.0;
  std::size_t occupied_cells = 0;     ///< of the map after the update
  std::size_t skipped_moving = 0;     ///< revolutions and frames of periods the robot moved in
  std::size_t skipped_version = 0;    ///< of another model version, or without a joint state
  std::uint64_t model_version = 0;
};
/// "planner: sensor map: used ... in N ms, ... hits; map N occupied cells; ...".
std::string describe(const SensorMapUpdate& update);

/// Ray-casts sensor data into an Environment. Immutable; one per model version (the self
/// filter uses that model's shapes). Parameters: Params::sensor_* and floor_height.
///
/// No-return beams (0) are skipped, not cleared: the simulator and real lidars report 0 both
/// for "nothing within range" and for returns they reject (too near, too weak: dark or
/// specular surfaces), so clearing along them could erase a real obstacle the planner must
/// avoid. Returns beyond sensor_max_range clear their ray up to that range (the range error
/// grows with distance; the planner needs the few metres around the robot).
class SensorMapper {
 public:
  /// Throws PlannerError if `model` is null or a sensor parameter is out of range.
  SensorMapper(std::shared_ptr<const PlanningModel> model, const Params& params);

  /// Map pose of a sensor frame (a URDF link) at the full joint vector `q_full` (base x, y, yaw
  /// in the map frame first, PlanningModel::full_from_named). Throws PlannerError naming an
  /// unknown frame or a q of the wrong size.
  [[nodiscard]] Eigen::Isometry3d sensor_pose(const Eigen::VectorXd& q_full,
                                              const std::string& frame) const;

  /// One lidar revolution taken from `map_T_sensor` while the robot stood at `q_full` (for the
  /// self filter). Throws PlannerError naming the lidar and the bad field (non-finite pose,
  /// ranges not rings x columns, no rings or columns, non-finite or negative range...); the
  /// map is then unchanged.
  SensorMapStats insert_lidar(Environment& environment, const hardware::LidarScan& scan,
                              const Eigen::Isometry3d& map_T_sensor,
                              const Eigen::VectorXd& q_full) const;

  /// The rays insert_lidar() would cast, without touching a map (to insert several sensors with
  /// one copy of the tree). Same checks and errors.
  [[nodiscard]] SensorRays lidar_rays(const hardware::LidarScan& scan,
                                      const Eigen::Isometry3d& map_T_sensor,
                                      const Eigen::VectorXd& q_full) const;

  /// Successive depth frames of one camera (same size and intrinsics) from `map_T_optical`
  /// (optical frame: z forward, x right, y down), averaged per pixel: a pixel counts when at
  /// least sensor_depth_min_valid of the frames read it, and its depth is the mean of those
  /// readings (the sensor's noise is independent per frame). Every sensor_depth_stride-th pixel
  /// in u and v is ray-cast. Throws PlannerError naming the camera and the fault (no frames,
  /// depth not width x height, bad intrinsics or scale, frames that differ); map unchanged.
  SensorMapStats insert_depth(Environment& environment,
                              const std::vector<hardware::RgbdFrame>& frames,
                              const Eigen::Isometry3d& map_T_optical,
                              const Eigen::VectorXd& q_full) const;

  /// The rays insert_depth() would cast, without touching a map. Same checks and errors.
  [[nodiscard]] SensorRays depth_rays(const std::vector<hardware::RgbdFrame>& frames,
                                      const Eigen::Isometry3d& map_T_optical,
                                      const Eigen::VectorXd& q_full) const;

  /// Every sensor of `batch` from its pose at `q_full` (sensor_pose): a sensor whose frame or
  /// data is bad is refused with the reason and the others are used.
  [[nodiscard]] BatchRays batch_rays(const SensorBatch& batch, const Eigen::VectorXd& q_full) const;

  /// True if map point `p` lies in a robot collision shape grown by sensor_self_padding at the
  /// link poses `link_poses` (PlanningModel::link_poses).
  [[nodiscard]] bool on_robot(const Eigen::Vector3d& p,
                              const std::vector<Eigen::Isometry3d>& link_poses) const;

  [[nodiscard]] const PlanningModel& model() const { return *model_; }

 private:
  /// A robot collision shape grown by the padding, placed in the map for one insert.
  struct PaddedShape {
    LinkShape::Type type = LinkShape::Type::kBox;
    Eigen::Isometry3d shape_T_map = Eigen::Isometry3d::Identity();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // map frame
    Eigen::Vector3d half =
        Eigen::Vector3d::Zero();  // box: half extents; cylinder: r, r, half length; sphere: r
    double radius = 0.0;          // bounding sphere
  };
  [[nodiscard]] std::vector<PaddedShape> padded_shapes(
      const std::vector<Eigen::Isometry3d>& link_poses) const;
  [[nodiscard]] static bool inside(const std::vector<PaddedShape>& shapes,
                                   const Eigen::Vector3d& p);
  /// Sorts map-frame returns into hits and clears.
  [[nodiscard]] SensorRays sort(const Eigen::Vector3d& origin,
                                const std::vector<Eigen::Vector3d>& ends,
                                const Eigen::VectorXd& q_full) const;
  void check_q(const Eigen::VectorXd& q_full, const std::string& what) const;

  std::shared_ptr<const PlanningModel> model_;
  Params params_;
};

}  // namespace concert::planner
