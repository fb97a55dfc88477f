#pragma once
// Localisation in the BIM occupancy map (paper section 5.3, "localization") from the planar scan
// the robot derives from its lidars and from the odometry: an AMCL-like particle filter on a
// likelihood field (odometry motion model, beam subsampling, low-variance resampling when the
// effective sample size drops, recovery by spreading particles over free space when the scan
// stops matching), followed by a Gauss-Newton scan-to-distance-field refinement of the best
// estimate. Plain C++/Eigen; no DDS.
//
// Frames: map (the grid's frame), odom (the odometry filter's frame), base (the robot's root
// link). Planar poses are (x [m], y [m], yaw [rad]); map_T_base = map_T_odom * odom_T_base.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <random>
#include <span>
#include <stdexcept>
#include <vector>

#include "concert/bim/occupancy_grid.hpp"

namespace concert::nav {

/// Bad localiser input or parameter; what() names it. The localiser's state is unchanged.
class LocaliserError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Distance [m] from `origin` (map frame) along the direction `angle` [rad] to the boundary of
/// the first occupied cell of `grid`, or `max_range` when there is none within it. Cells
/// outside the grid count as occupied (as OccupancyGrid::occupied). Exact grid traversal
/// (Amanatides-Woo); 0 when `origin` lies in an occupied cell.
double cast_ray(const bim::OccupancyGrid& grid, const Eigen::Vector2d& origin, double angle,
                double max_range);

/// Distance from every point of the map to the nearest occupied cell: exact Euclidean distance
/// transform (Felzenszwalb-Huttenlocher) of the cell centres, read with bilinear interpolation.
/// Immutable; share it between localisers of the same map.
class LikelihoodField {
 public:
  /// Throws LocaliserError for a grid with no cells, a wrong cell count, no occupied cell or a
  /// max_distance that is not positive.
  LikelihoodField(bim::OccupancyGrid grid, double max_distance = 2.0);

  /// Distance [m] from map point `p` to the nearest occupied cell's boundary (the bilinear
  /// cell-centre distance less half a cell, >= 0), capped at max_distance(); max_distance()
  /// outside the grid.
  [[nodiscard]] double distance(const Eigen::Vector2d& p) const;
  /// Same, with its gradient d(distance)/dp [-] (zero inside occupied cells and outside).
  [[nodiscard]] double distance(const Eigen::Vector2d& p, Eigen::Vector2d& gradient) const;

  [[nodiscard]] const bim::OccupancyGrid& grid() const { return grid_; }
  [[nodiscard]] double max_distance() const { return max_distance_; }
  /// Centres of the free cells at least `clearance` [m] from any occupied cell (map frame).
  [[nodiscard]] std::vector<Eigen::Vector2d> free_cells(double clearance) const;

 private:
  bim::OccupancyGrid grid_;
  double max_distance_;
  std::vector<float> centre_distance_;  // [m] per cell, row-major as grid_.cells
};

/// A planar scan in the base frame: beam i has bearing angles[i] [rad] about the base z axis
/// from its x axis and range ranges[i] [m]. A range that is not finite or outside
/// [range_min, range_max] is no return (ignored). hardware::LaserScan2d maps onto it directly.
struct PlanarScan {
  std::vector<double> angles;
  std::vector<double> ranges;
  double range_min{0.0};   ///< [m]
  double range_max{30.0};  ///< [m]
};

/// Parameters of the localiser. Defaults suit the CONCERT base's 720-bin scan at 10 Hz.
struct LocaliserParams {
  int particles{1000};             ///< particles while tracking (fixed count)
  int recovery_particles{30000};   ///< particles spread over free space when lost
  double recovery_clearance{0.3};  ///< spread only where the base's centre can be [m]
  int max_beams{60};               ///< beams per particle weighting (evenly subsampled)
  double sigma_hit{0.1};           ///< std-dev of the likelihood field [m]
  double z_hit{0.9};               ///< weight of the hit model [-]
  double z_rand{0.1};              ///< weight of the uniform random-return model [-]
  /// Exponent of each beam's likelihood (< 1: neighbouring beams are not independent, and the
  /// posterior would otherwise collapse on one particle) [-].
  double beam_exponent{0.25};
  /// Odometry motion noise: translation std-dev per metre and per radian, rotation std-dev per
  /// radian and per metre [m/m, m/rad, rad/rad, rad/m].
  double alpha_trans_trans{0.1};
  double alpha_trans_rot{0.05};
  double alpha_rot_rot{0.1};
  double alpha_rot_trans{0.05};
  /// The filter weighs particles only after this much motion since its last weighting [m, rad].
  double update_min_distance{0.03};
  double update_min_angle{0.03};
  double resample_ratio{0.5};  ///< resample when N_eff < ratio * N
  /// The estimate: the mean of the particles within cluster_radius [m] and cluster_angle [rad]
  /// of the heaviest cell of a (cluster_radius, cluster_radius, cluster_angle) histogram.
  double cluster_radius{0.5};
  double cluster_angle{0.5};
  /// Gauss-Newton refinement of the estimate against the distance field.
  bool refine{true};
  int refine_beams{240};
  int refine_iterations{10};
  double refine_outlier{0.25};   ///< beams farther than this from the map are left out [m]
  double refine_max_shift{0.3};  ///< a larger correction is refused [m]
  double refine_max_turn{0.2};   ///< [rad]
  /// A beam within this distance of the map matches [m]; the match ratio is the fraction of
  /// returns that match at the estimate.
  double match_distance{0.15};
  /// Below this for lost_after scans: lost, particles spread (again while lost: a wrong
  /// cluster is dropped).
  double lost_match_ratio{0.3};
  int lost_after{10};
  /// lost -> tracking after converged_after consecutive weighed scans with the match ratio
  /// above converged_match_ratio, the estimate refined, and the cluster's spread below:
  int converged_after{5};
  double converged_match_ratio{0.7};
  double converged_sigma_xy{0.2};   ///< ... and the cluster's position std-dev below this [m]
  double converged_sigma_yaw{0.1};  ///< ... and its yaw std-dev below this [rad]
  std::uint64_t seed{1};
};

/// Whether the estimate can be used.
enum class LocaliserStatus {
  kUninitialised,  ///< no pose given and no scan yet
  kTracking,       ///< the estimate follows the robot
  kLost,           ///< particles spread over the map; the estimate is not to be used
};

/// The localiser's output.
struct LocaliserEstimate {
  LocaliserStatus status{LocaliserStatus::kUninitialised};
  Eigen::Vector3d pose{Eigen::Vector3d::Zero()};        ///< map_T_base (x, y, yaw)
  Eigen::Vector3d map_T_odom{Eigen::Vector3d::Zero()};  ///< (x, y, yaw)
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Zero()};  ///< of pose: the particle cluster's
  double match_ratio{0.0};          ///< fraction of returns within match_distance of the map
  bool refined{false};              ///< the Gauss-Newton refinement was applied
  double effective_particles{0.0};  ///< N_eff after the last weighting
  int low_match_updates{0};         ///< consecutive scans with match_ratio < lost_match_ratio
};

/// One pose hypothesis.
struct Particle {
  Eigen::Vector3d pose{Eigen::Vector3d::Zero()};  ///< map_T_base
  double weight{0.0};                             ///< normalised
};

/// The particle filter. Not thread-safe: one owner feeds it odometry and scans in time order.
class Localiser {
 public:
  /// Throws LocaliserError naming a parameter out of range, or for a null field.
  Localiser(std::shared_ptr<const LikelihoodField> field, const LocaliserParams& params = {});

  /// Initial pose from the user: particles drawn around `map_pose` with std-devs `sigma`
  /// (x, y [m], yaw [rad]); `odom_pose` is odom_T_base at that moment. Status: tracking.
  void set_pose(const Eigen::Vector3d& map_pose, const Eigen::Vector3d& sigma,
                const Eigen::Vector3d& odom_pose);
  /// Global localisation: recovery_particles spread over free space. Status: lost.
  void spread(const Eigen::Vector3d& odom_pose);

  /// Moves the particles by the odometry since the last call, weighs them with the scan (after
  /// enough motion), resamples, and estimates the pose. The first update without set_pose()
  /// spreads the particles (lost). Throws LocaliserError (state kept) for a non-finite
  /// odometry pose, angle or range limit, or angles and ranges of different sizes.
  const LocaliserEstimate& update(const Eigen::Vector3d& odom_pose, const PlanarScan& scan);

  [[nodiscard]] const LocaliserEstimate& estimate() const { return estimate_; }
  [[nodiscard]] std::span<const Particle> particles() const { return particles_; }
  [[nodiscard]] const LocaliserParams& params() const { return params_; }

 private:
  struct Beam {
    double x, y;  // end point in the base frame [m]
  };
  void collect_beams(int count, std::vector<Beam>& out) const;
  void move_particles(const Eigen::Vector3d& delta);
  void weigh_particles();
  void resample(int count);
  void estimate_pose(const Eigen::Vector3d& odom_pose);
  bool refine(Eigen::Vector3d& pose) const;
  [[nodiscard]] double match_ratio(const Eigen::Vector3d& pose) const;

  std::shared_ptr<const LikelihoodField> field_;
  LocaliserParams params_;
  std::mt19937_64 rng_;
  std::vector<Particle> particles_;
  std::vector<Particle> scratch_;
  std::vector<Beam> weigh_beams_;
  std::vector<Beam> refine_beams_;
  std::vector<Beam> all_beams_;
  std::vector<double> log_likelihood_;
  std::vector<double> beam_log_likelihood_;  // per millimetre of distance to the map
  int converging_updates_{0};
  bool have_odom_{false};
  Eigen::Vector3d last_odom_{Eigen::Vector3d::Zero()};
  Eigen::Vector3d motion_since_weighing_{Eigen::Vector3d::Zero()};
  bool weigh_next_{true};
  LocaliserEstimate estimate_;
};

}  // namespace concert::nav
