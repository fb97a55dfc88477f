#pragma once
// From camera frames to drilling areas and holes (paper sections 5.4.1 and 5.4.3): where a
// picked point or pixel lies on the wall and its normal, the holes an area's marks ask for,
// and the blob a servoed hole follows. Uses the perception functions (perception.hpp,
// patterns.hpp) on a frame whose pose in the world is known. Plain C++, no DDS.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "drill/mission.hpp"
#include "drill/ports.hpp"

namespace concert::drill {

class PatternTable;

/// A camera frame (depth averaged over a few frames) and where the camera was.
struct CameraView {
  const hardware::RgbdFrame* frame{nullptr};
  Eigen::Isometry3d world_T_optical{Eigen::Isometry3d::Identity()};
};

/// The paper's drilling-area radius for a camera with vertical field of view `fov` [rad] at
/// `distance` [m] from the wall: rho = d tan(fov / 2) (0.6 m, 55 deg: 0.31 m).
double area_radius(double distance, double fov);

/// The smaller field of view of a pinhole image [rad] (its height's for a landscape one).
double smaller_fov(const hardware::CameraIntrinsics& k);

/// How far out [m] a camera with smaller field of view `fov` [rad] must stand for every point
/// within `radius` [m] of where it looks to be in its image however it rolls about its axis
/// (area_radius's inverse, with 10 % of the half-angle kept as margin): the planner leaves a
/// looking camera's roll free.
double any_roll_distance(double radius, double fov);

/// Room left around an ArUco marker for the odometry's drift when the camera is turned onto it
/// after a base move [m]: over the pattern test's whole-body moves odometry is up to 52 mm off
/// the simulator's truth.
inline constexpr double kMarkerLookDrift = 0.05;

/// How far from a marker's centre a look at it must see, whichever way the camera rolls [m]:
/// its half-diagonal (`marker_size` [m] a side) and `drift` around it.
/// any_roll_distance(marker_look_radius(...), fov) is how near the camera may come: from the
/// camera's distance at a drilling posture (0.22 m on morphology A) the marker fills the image
/// past its edge and is not found.
double marker_look_radius(double marker_size, double drift = kMarkerLookDrift);

/// Where a camera looks to see a blob hole and its nearest neighbour of the area together.
struct BlobPairView {
  Eigen::Vector3d centre;  ///< midway between the two blobs (world) [m]
  double radius{0.0};      ///< half their distance plus the room for drift [m]
};

/// The view framing `hole`'s blob and the area's blob nearest to it (markers and the hole
/// itself skipped, told by label), with `drift` [m] of room around both; none without a
/// neighbour. Seen together, the pair names each blob (blob_shift) where one blob seen alone
/// could be the neighbour; any_roll_distance(radius, fov) is how far out to look from.
std::optional<BlobPairView> blob_pair_view(const DrillPoint& hole, const std::vector<DrillPoint>& area_points,
                                           double drift);

/// Whether a world point projects into the view's image (in front of the camera).
bool in_view(const CameraView& view, const Eigen::Vector3d& point);

/// The frame of a picked point no camera sees yet: origin at the point, z horizontal from the
/// point towards `viewer` (the wall assumed vertical and facing the robot), x horizontal, y up.
/// The approach is planned to it; the drill camera measures the surface once there.
ResolvedArea provisional_area(const Eigen::Vector3d& point, const Eigen::Vector3d& viewer);

/// Locates a point or pixel area in a view: the surface point and its normal (PCL, within
/// 0.07 m), the frame z along the outward normal, x horizontal, y up (world frame). Throws
/// DrillError naming the area and why (outside the image, no depth there).
ResolvedArea locate_area(const AreaSpec& area, const CameraView& view);

/// The holes an area's marks ask for in a view: blobs within `radius` of the area's centre,
/// nearest first (servo on), or the pattern of the ArUco marker nearest the centre (servo
/// off), each with its frame on the wall (world frame, z along the outward normal). Throws
/// DrillError with the reason when nothing can be drilled (no blob visible, no marker, a
/// marker id without a pattern).
std::vector<DrillPoint> find_holes(const AreaSpec& area, const ResolvedArea& located,
                                   const CameraView& view, const PatternTable& patterns,
                                   double radius);

/// A hole re-measured in a fresh view (the base moved since it was detected, and odometry
/// drifts: 3.5 deg of yaw over the demo's approach): a blob hole at the blob nearest its
/// predicted position (within `max_distance` [m]), the frame from the surface there; an ArUco
/// hole from its marker when the marker is in view (moved by the marker's shift,
/// hole_of_seen_marker); else the
/// surface under the predicted position (its normal and distance corrected, the position in
/// the wall's plane kept). None when the view shows neither the mark nor the wall there.
std::optional<Eigen::Isometry3d> reanchor(const CameraView& view, const DrillPoint& hole,
                                          const PatternTable& patterns, double max_distance);

/// Where the marker of an ArUco hole stands (world frame, z out of the wall), from the hole's
/// frame and its pattern; none for a blob hole or a marker without a pattern.
std::optional<Eigen::Isometry3d> marker_of(const DrillPoint& hole, const PatternTable& patterns);

/// An ArUco hole's frame from where its marker stands (`world_T_marker`: the pattern applied);
/// none for a blob hole or a marker without a pattern.
std::optional<Eigen::Isometry3d> hole_of(const DrillPoint& hole,
                                         const Eigen::Isometry3d& world_T_marker,
                                         const PatternTable& patterns);

/// An ArUco hole moved by its marker seen again (`seen`: where the marker stands now, world
/// frame): by the shift of the marker's centre only, the pattern's orientation kept from the
/// hole's frame. After a base move the marker is seen from aside, near the image's edge, and its
/// orientation comes out a few degrees off, while the row's ends lie 0.34 m from it: applied with
/// the seen orientation, holes on morphology A come out 7-14 mm off; the
/// centre, on the depth image's plane, is good to a millimetre, and the orientation measured
/// first (straight on, 0.6 m away, frames averaged) moves with the odometry's yaw (the gyro's).
/// None for a blob hole or a marker without a pattern.
std::optional<Eigen::Isometry3d> hole_of_seen_marker(const DrillPoint& hole,
                                                     const Eigen::Isometry3d& seen,
                                                     const PatternTable& patterns);

/// Where marker `id` stands in a view (world frame, depth-refined), if it is detected; of
/// several markers with that id, the one nearest `near` (world frame).
std::optional<Eigen::Isometry3d> find_marker(const CameraView& view, int id,
                                             const Eigen::Vector3d& near,
                                             const PatternTable& patterns);

/// How an area's blobs appear in a view against where they were predicted (blob_shift).
struct AreaShift {
  Eigen::Vector3d by{Eigen::Vector3d::Zero()};  ///< world frame [m]
  int blobs{0};  ///< predicted blobs it lays onto seen ones (2 or more: the set confirms it)
};

/// How far the blobs of an area appear from where they were predicted (world frame, [m]): the
/// shift that lays the most predicted blob positions of `area_points` onto blobs seen in the
/// view (within `tolerance`), among the shifts no longer than `max_shift` (the most odometry
/// can have drifted since the area was detected); ties go to the smallest shift. Blobs 0.1 m
/// apart and a prediction off by 5 cm are told apart this way where the nearest blob would be
/// the wrong one; a hole's own blob out of the image is placed by its neighbours. None when no
/// blob is in view within `max_shift`, or when two different shifts explain the view equally
/// well (one blob seen alone, within `max_shift` of two predicted ones): a neighbour is not
/// taken for the target.
///
/// A shift that lays two or more blobs onto seen ones may be as long as `max_set_shift` (when
/// longer than `max_shift`): the set's own geometry names each blob, where one blob seen alone
/// 0.1 m from a prediction off by 0.1 m is the neighbour as well as anything (a whole-body move
/// on the demo can drift odometry 87 mm).
std::optional<AreaShift> blob_shift(const CameraView& view, const std::vector<DrillPoint>& area_points,
                                    double tolerance, double max_shift, double max_set_shift = 0.0);

/// The blob nearest to `hole` in a view (world frame, within `max_distance` [m]), as a hole
/// frame with the observed position and normal; none if no blob is that close.
std::optional<Eigen::Isometry3d> track_blob(const CameraView& view, const Eigen::Isometry3d& hole,
                                            double max_distance);

}  // namespace concert::drill
