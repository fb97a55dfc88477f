#pragma once
// The drilling service's perception on the drill camera's RGB-D frames (paper sections 5.4.1 and
// 5.4.3): blue blobs, ArUco markers, the surface normal and the drilling area's frame, and the
// per-pixel averaging of successive depth images. Plain C++ (OpenCV, PCL), no DDS.
//
// Frames and pixels follow hardware/sensors.hpp: everything is in the camera's optical frame
// (z along the optical axis, x to the image's right, y down) [m]; pixel (u, v) is column u, row
// v, with its centre at (u, v). Depth is z along the axis (not the range along the ray), read
// with the frame's depth_scale, so the averaged frames of DepthAverager (0.1 mm steps) and the
// camera's own (1 mm) are read alike.
//
// Every function checks the frame first (check_frame) and throws DrillError naming the frame
// (sensor, stamp) and what is wrong.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "concert/hardware/sensors.hpp"
#include "drill/mission.hpp"

namespace concert::drill {

// --- Frames, pixels and points ------------------------------------------------------------------

/// Throws DrillError unless `frame` is usable: width and height > 0, rgb of width * height * 3
/// values, depth of width * height, focal lengths and depth_scale > 0 and finite.
void check_frame(const hardware::RgbdFrame& frame);

/// "rgbd frame 'camera_E' at t = 12.300 s": how errors name a frame.
std::string describe(const hardware::RgbdFrame& frame);

/// The point of the optical frame at `depth` [m] (z) on the ray of `pixel` [px].
Eigen::Vector3d deproject(const hardware::CameraIntrinsics& k, const Eigen::Vector2d& pixel,
                          double depth);
/// The pixel [px] a point of the optical frame (z > 0) projects to.
Eigen::Vector2d project(const hardware::CameraIntrinsics& k, const Eigen::Vector3d& point);

/// The surface point seen at `pixel`: the median of the valid depths within `radius` [px] of
/// it (0: the pixel itself), deprojected on the pixel's ray. Throws DrillError naming the
/// pixel and the frame if the pixel is outside the image or no depth lies within the radius.
Eigen::Vector3d point_at_pixel(const hardware::RgbdFrame& frame, const Eigen::Vector2d& pixel,
                               double radius = 2.0);

/// Writes the frame's colour image to `path` as a PNG, with a red cross and circle on `mark`
/// [px] when given (where a mark was looked for): how an engineer sees what the drill camera
/// saw when a mark was not found (concert_drill --unseen-frames). Throws DrillError naming
/// the path when it cannot be written.
void write_view_png(const hardware::RgbdFrame& frame, const std::string& path,
                    const std::optional<Eigen::Vector2d>& mark = std::nullopt);

// --- Depth averaging (section 5.4.1) ------------------------------------------------------------

/// Averages the depth images of successive frames of a still camera pixel by pixel ("progressive
/// point cloud acquisitions are averaged in time relying on the position in pixel of each
/// point"): each pixel's depth is the mean of its valid (non-zero) readings in the last
/// `window` frames. Averaging n frames divides the sensor's per-pixel noise by sqrt(n). The
/// camera must not move meanwhile: clear() after it moved.
class DepthAverager {
 public:
  /// `window`: frames averaged (>= 1); `min_valid`: fraction of the frames in the window that
  /// must have read a pixel for it to count (0..1]; a pixel read fewer times (an edge that
  /// flickers, a dark spot) is 0 (no data) in the average. Throws DrillError on bad values.
  explicit DepthAverager(std::size_t window = 10, double min_valid = 0.5);

  /// Adds a frame (the oldest drops out once the window is full). Throws DrillError if the
  /// frame is bad or its image size or intrinsics differ from the frames already added.
  void add(const hardware::RgbdFrame& frame);
  /// Forgets every frame.
  void clear();
  /// Frames in the window.
  [[nodiscard]] std::size_t size() const { return frames_.size(); }
  [[nodiscard]] std::size_t window() const { return window_; }

  /// The latest frame (colour, sensor, stamp, intrinsics) with the averaged depth, in steps of
  /// 0.1 mm (depth_scale 1e-4; coarser, 65535 steps over the farthest depth, beyond 6.5 m).
  /// Throws DrillError if no frame was added.
  [[nodiscard]] hardware::RgbdFrame average() const;

 private:
  std::size_t window_;
  double min_valid_;
  std::vector<std::vector<float>> frames_;  ///< depth [m] of the frames in the window, oldest first
  std::vector<double> sum_;                 ///< per pixel, of the valid depths in the window [m]
  std::vector<std::uint16_t> count_;        ///< per pixel, valid depths in the window
  hardware::RgbdFrame latest_;              ///< the latest frame as added
};

// --- Blue blobs (section 5.4.3) -----------------------------------------------------------------

/// What a blue blob is. Colour thresholds are OpenCV's 8-bit HSV (hue 0..180, saturation and
/// value 0..255); sizes are metric so one set works from 0.4 m to 2.5 m.
struct BlobParams {
  int hue_min{95};  ///< blue is hue 120; marker-pen blue 100..125
  int hue_max{135};
  int saturation_min{100};    ///< grey walls, white and black have saturation ~0
  int value_min{40};          ///< darker than this is too dark to tell the hue
  double min_diameter{0.01};  ///< [m] smaller spots are noise or specks
  double max_diameter{0.06};  ///< [m] larger blue areas are not pen marks
  /// 4 pi area / perimeter^2 of the blob's outline: 1 for a disc, 0.86..0.92 for the digitised
  /// discs of 2-3 cm blobs from 0.6 m to 2.5 m, ~0.2 for an 8 x 100 px pen stroke. Lower is not
  /// a blob.
  double min_circularity{0.7};
  double min_radius_px{2.0};  ///< [px] smaller images are too few pixels to tell a shape
  /// Blobs whose image touches the image border (cut off: wrong centre) are left out.
  int border_px{2};
};

/// One blue blob.
struct Blob {
  Eigen::Vector2d pixel{0.0, 0.0};  ///< centre (centroid of its pixels) [px]
  double radius_px{0.0};            ///< of the disc its pixels make (from their second moments, the
                                    ///< major axis if seen at an angle) [px]
  Eigen::Vector3d position{0.0, 0.0, 0.0};  ///< centre on the surface, optical frame [m]
  double diameter{0.0};                     ///< [m]
  double circularity{0.0};                  ///< 4 pi area / perimeter^2 of its outline
  int depth_samples{0};                     ///< valid depth pixels behind it
};

/// The blue blobs of a frame, largest first: pixels within the HSV range (opened by a 3 x 3
/// ellipse to drop single-pixel specks), their outer contours (cv::findContours: a
/// contour gives the outline for the circularity and, filled, the pixel region for the centroid
/// and size; SimpleBlobDetector sweeps grey thresholds that a binary mask makes pointless and
/// filters sizes in pixels only, while ours must be metric, from depth, per blob), each kept if
/// circular and of a metric diameter within the bounds. Position: the interquartile mean (mean
/// of the middle half: as robust to holes and outliers as the median, less noisy, and not
/// quantised to the camera's 1 mm steps) of the valid depths of the blob's pixels, on the
/// centroid's ray. A blob with no valid depth behind it is left out (its size cannot be told).
std::vector<Blob> detect_blobs(const hardware::RgbdFrame& frame, const BlobParams& params = {});

// --- ArUco markers (section 5.4.3) --------------------------------------------------------------

struct ArucoParams {
  std::string dictionary{"DICT_4X4_50"};  ///< OpenCV predefined dictionary name
  double marker_size{0.1};                ///< printed side, border included [m] (PnP only)
  /// Refine the pose with the depth image: a plane fitted to the depth of the marker's pixels
  /// (the inverse depth regressed on the image coordinates, robust to outliers), the corner
  /// rays intersected with it, the marker frame of those corners (marker_frame). Position and
  /// normal then come from thousands of depth pixels instead of four corners: 0.1-0.6 mm and
  /// < 0.3 degrees off at 0.6-1 m where PnP is 1.6-5.6 mm off, and PnP alone takes the mirror
  /// solution of a small marker seen square-on at 1 m (9 degrees, 4 cm at the pattern's holes;
  /// perception_test). Off: PnP alone.
  bool refine_with_depth{true};
  /// Fewest valid depth pixels on the marker for the depth refinement (else PnP alone).
  int min_depth_samples{50};
};

/// One detected marker. The marker frame is the one of patterns.hpp: origin at the centre,
/// z out of the marker towards the camera, x the marker's right, y its up.
struct ArucoDetection {
  int id{-1};
  std::string dictionary;
  /// Outer corners [px] in OpenCV's order: top-left, top-right, bottom-right, bottom-left of
  /// the upright marker (world::MarkTruth::corners' order), sub-pixel.
  std::array<Eigen::Vector2d, 4> corners{};
  /// The pose: depth-refined if depth_refined, else pnp.
  Eigen::Isometry3d optical_T_marker{Eigen::Isometry3d::Identity()};
  /// PnP alone (cv::solvePnP, SOLVEPNP_IPPE_SQUARE on the corners, marker_size).
  Eigen::Isometry3d pnp{Eigen::Isometry3d::Identity()};
  bool depth_refined{false};
  /// Side measured from the depth-refined corners [m] (0 without refinement): a marker printed
  /// at another size than ArucoParams::marker_size shows here.
  double measured_size{0.0};
  double reprojection_error{0.0};  ///< RMS of the PnP pose's corner reprojection [px]
};

/// The markers of `params.dictionary` in a frame (cv::aruco::detectMarkers, sub-pixel corner
/// refinement), in id order. Throws DrillError for an unknown dictionary (naming the accepted
/// ones) or a marker_size <= 0.
std::vector<ArucoDetection> detect_aruco(const hardware::RgbdFrame& frame,
                                         const ArucoParams& params = {});

/// The marker frame of a square's outer corners [m] in OpenCV's order (top-left, top-right,
/// bottom-right, bottom-left, seen from the front): origin at their mean, z the normal towards
/// the front, x along the top and bottom edges (left to right), y = z x x. Throws DrillError if
/// the corners are degenerate (coincident or collinear).
Eigen::Isometry3d marker_frame(const std::array<Eigen::Vector3d, 4>& corners);

// --- Surface normal and drilling area frame (section 5.4.1) -------------------------------------

/// How the normal at a picked point is estimated (PCL).
struct SurfaceParams {
  /// pcl::VoxelGrid leaf [m]. Not 1 cm: the grid's cubes cut a noisy oblique surface into steps
  /// that tilt its normals, 0.4-0.5 degrees at 0.6 m with the RealSense's noise (0.03-0.1 with
  /// 5 mm, perception_test).
  double voxel{0.005};
  double normal_radius{0.03};  ///< neighbourhood of each point's normal (pcl::NormalEstimation) [m]
  double average_radius{0.07};  ///< normals averaged within this of the picked point [m] (paper)
  int min_normals{5};           ///< fewer points with a normal within average_radius: an error
};

/// A surface point and its normal.
struct SurfacePatch {
  Eigen::Vector3d point{0.0, 0.0, 0.0};    ///< on the surface, optical frame [m]
  Eigen::Vector3d normal{0.0, 0.0, -1.0};  ///< unit, towards the camera
  int normals{0};                          ///< downsampled points whose normals were averaged
};

/// The surface at `pixel`: the frame's depth as a point cloud, voxel-downsampled, a PCL normal
/// at every point (oriented towards the camera), the normals within average_radius of the
/// pixel's point (point_at_pixel) averaged; the point is where the pixel's ray meets the plane
/// through those points' centroid with that normal (so a hole in the depth at the pixel itself
/// does not matter if there is depth within 5 px). Throws DrillError naming the pixel if there
/// is no depth there or too few points around it.
SurfacePatch surface_at(const hardware::RgbdFrame& frame, const Eigen::Vector2d& pixel,
                        const SurfaceParams& params = {});
/// The same at a point of the optical frame [m] (e.g. a point of the map seen by the camera),
/// moved onto the surface along the normal.
SurfacePatch surface_at(const hardware::RgbdFrame& frame, const Eigen::Vector3d& point,
                        const SurfaceParams& params = {});

/// A drilling area frame optical_T_area from a surface patch: origin at the point, z the normal
/// (towards the camera), x horizontal (perpendicular to `up_in_optical`, the world's up seen in
/// the optical frame), y = z x x (up along the surface). Throws DrillError if the normal is
/// within 1 degree of `up` (a floor or ceiling: no horizontal direction in it).
Eigen::Isometry3d area_frame(const SurfacePatch& patch, const Eigen::Vector3d& up_in_optical);

/// area_frame(surface_at(frame, pixel), up_in_optical).
Eigen::Isometry3d area_frame_at(const hardware::RgbdFrame& frame, const Eigen::Vector2d& pixel,
                                const Eigen::Vector3d& up_in_optical,
                                const SurfaceParams& params = {});
/// area_frame(surface_at(frame, point), up_in_optical).
Eigen::Isometry3d area_frame_at(const hardware::RgbdFrame& frame, const Eigen::Vector3d& point,
                                const Eigen::Vector3d& up_in_optical,
                                const SurfaceParams& params = {});

}  // namespace concert::drill
