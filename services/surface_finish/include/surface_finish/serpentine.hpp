#pragma once
// The serpentine path over a rectangle (paper section 5.7): vertical strokes, left to right,
// alternately up and down, joined at the top and bottom; the stroke count from the rectangle's
// width and the tool's coat width with overlap; time-parameterised at the user's speed
// (trapezoidal speed on every segment); solved joint by joint along the way and refused with a
// reason before anything moves if any sample is unreachable. No DDS.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "surface_finish/reach.hpp"
#include "surface_finish/types.hpp"

namespace concert::surface_finish {

struct PathParams {
  double speed{0.2};          ///< TCP speed along the strokes [m/s]
  double acceleration{0.5};   ///< [m/s^2]
  double sample_period{0.02}; ///< time between samples [s]
  double approach{0.05};      ///< the path starts and ends this far further off the wall [m]
  double approach_speed{0.1}; ///< [m/s]
  /// Painted threshold of the coat as a fraction of the nominal film (as DepositionParams::visible):
  /// the strokes reach far enough beyond the rectangle for its corners to reach it. Sanding: 0.
  double visible{0.1};
  /// Each stroke ends with the TCP held at its end this long [s], the valve still driven by
  /// the measured position (valve_open), so a TCP that lags its target still paints the whole
  /// stroke and no further: up and down strokes end alike (the paper's delta h).
  double settle{0.4};
  /// Largest joint speed of the path as a fraction of each joint's velocity limit [-].
  double velocity_scale{0.8};
  /// The joint-space move from the current posture ends at least this far from the wall [m];
  /// when the approach pose is nearer (sanding: 5 cm), a straight line along the normal at the
  /// approach speed leads from there to it. The move itself keeps the TCP 5 cm off the wall, so
  /// it cannot end at 5 cm: arriving obliquely, it dips under the pose it goes to.
  double move_standoff{0.1};
  /// The joint-space move keeps the TCP this far off the wall [m], or, when it starts nearer
  /// (a run ends backed off by `approach`, and the next starts there within the tracking's
  /// error), no nearer than where it starts less `start_tolerance`.
  double move_clearance{0.05};
  /// The same for every collision primitive of the arm and its tool (a tilted disc's rim comes
  /// nearer the wall than its TCP; the TCP's 5 cm leave a 0.23 m disc's rim at 46-49 mm on the
  /// sanding robot's moves) [m].
  double move_shape_clearance{0.03};
  double start_tolerance{0.002};  ///< [m]
};

/// One vertical stroke, in wall coordinates.
struct Stroke {
  double x{0.0};       ///< lateral position of the TCP [m]
  double y_start{0.0}; ///< height where the stroke starts (bottom when going up) [m]
  double y_end{0.0};
  [[nodiscard]] bool up() const { return y_end > y_start; }
};

/// One sample of the timed path.
struct PathSample {
  double t{0.0};                 ///< [s] from the path's start
  Eigen::Vector3d wall{0, 0, 0}; ///< wall coordinates x, y [m] and offset from the wall [m]
  Eigen::Isometry3d tcp{Eigen::Isometry3d::Identity()};  ///< TCP target, base frame
  Eigen::VectorXd q;             ///< fixed-base joint positions reaching it
  Eigen::VectorXd qd;            ///< joint velocities (finite differences) [rad/s]
  int stroke{-1};                ///< index of the stroke being painted, -1 on approach / joins
  bool tool_on{false};           ///< spraying (or sanding) on this sample
};

/// A planned serpentine.
struct SerpentinePlan {
  Rect rect;                     ///< the rectangle to cover
  ToolSpec tool;
  PathParams params;
  double roll{0.0};
  double spacing{0.0};           ///< distance between adjacent strokes [m]
  double end_extension{0.0};     ///< how far the strokes' centres reach beyond rect +- coat/2 [m]
  std::vector<Stroke> strokes;
  std::vector<PathSample> samples;
  [[nodiscard]] double duration() const { return samples.empty() ? 0.0 : samples.back().t; }
};

/// Whether the spray valve is open for a TCP measured at wall coordinates `tcp_wall` while
/// stroke `stroke` runs: between the stroke's start and end heights along its direction. The
/// valve follows the measured position, not the clock.
bool valve_open(const Stroke& stroke, const Eigen::Vector3d& tcp_wall);

/// The plan sample a measured posture `q` is at, tracked forwards from sample `from`: the nearest
/// of the next `window` samples (and `from` itself) over the arm's joints `arm` alone. The legs'
/// steering and wheel joints stand where the base was driven, which the plan's seed postures do
/// not know.
std::size_t track_sample(const SerpentinePlan& plan, const std::vector<int>& arm, std::size_t from,
                         const Eigen::VectorXd& q, std::size_t window = 40);

/// Number of strokes covering `width` [m] with coats `coat_width` wide overlapping by
/// `overlap` (a fraction): 1 when width <= coat_width, else ceil((width - coat) / (coat (1 -
/// overlap))) + 1. Throws FinishError for non-positive sizes or overlap outside [0, 0.9].
int stroke_count(double width, double coat_width, double overlap);

/// The strokes over `rect` (centres from x0 + coat/2 to x1 - coat/2, evenly spaced; ends such
/// that the coat covers the rectangle's corners between strokes, see end_extension).
std::vector<Stroke> serpentine_strokes(const Rect& rect, const ToolSpec& tool, double visible = 0.1,
                                       double* spacing = nullptr, double* end_extension = nullptr);

/// Plans and checks the whole path: a joint-space move from `q_start` to the approach pose
/// (self-collision checked), approach from `approach` [m] further off, strokes, joins,
/// retreat; every sample solved from its predecessor (the first from `q_start`) and checked
/// for reach, limits, self-collision, singularity and continuity, and every joint's speed
/// between samples against its velocity limit. Throws FinishError naming the first sample that
/// fails ("stroke 3 at (0.25, 1.90) m: IK 12 mm short").
/// `path_seed`: the IK seed of the approach pose (AreaMap::posture_near the first stroke's
/// start keeps the path on the area's branch); nullptr: q_start.
SerpentinePlan plan_serpentine(Reach& reach, const WallFrame& wall, const Rect& rect, const ToolSpec& tool,
                               double roll, const PathParams& params, const Eigen::VectorXd& q_start,
                               const Eigen::VectorXd* path_seed = nullptr);

}  // namespace concert::surface_finish
