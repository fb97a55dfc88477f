// ArUco markers: OpenCV's detector, PnP (IPPE_SQUARE) and the refinement with the depth image.
#include "concert/world/aruco.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "concert/world/world.hpp"
#include "drill/perception.hpp"
#include "frame_access.hpp"

namespace concert::drill {

namespace {

cv::Ptr<cv::aruco::Dictionary> dictionary(const std::string& name) {
  try {
    world::aruco_dictionary_size(name);  // names the accepted dictionaries if `name` is not one
  } catch (const world::WorldError& e) {
    throw DrillError(std::string("ArUco detection: ") + e.what());
  }
  // aruco_dictionary_names() is in the order of OpenCV's PREDEFINED_DICTIONARY_NAME.
  const auto& names = world::aruco_dictionary_names();
  return cv::aruco::getPredefinedDictionary(
      static_cast<int>(std::find(names.begin(), names.end(), name) - names.begin()));
}

Eigen::Isometry3d pose(const cv::Vec3d& rvec, const cv::Vec3d& tvec) {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      t.linear()(i, j) = r(i, j);
    }
    t.translation()[i] = tvec[i];
  }
  return t;
}

/// A plane seen by the camera as the inverse depth it puts on the normalised image points
/// m = (x / z, y / z, 1): a point X = z m lies on the plane iff 1 / z = v . m. Fitted by linear
/// least squares of 1 / z on m (then again without the points farther than 3 robust standard
/// deviations). Not a PCA of the 3D points: the camera's noise is along the rays (depth), and a
/// PCA, which assumes isotropic noise, tilts an oblique plane's normal towards the optical axis
/// by ~ (sigma_z / extent)^2 (0.6 degrees for a 10 cm marker turned 25 degrees at 1 m). The
/// RealSense's depth noise grows as z^2, so 1 / z has about the same noise everywhere.
struct InverseDepthPlane {
  Eigen::Vector3d v{Eigen::Vector3d::Zero()};
  /// Where the ray through m meets the plane.
  [[nodiscard]] Eigen::Vector3d on_ray(const Eigen::Vector3d& m) const { return m / v.dot(m); }
  /// Unit normal towards the camera.
  [[nodiscard]] Eigen::Vector3d normal() const { return -v.normalized(); }
};

/// `m`: normalised image points; `w`: their inverse depths [1/m]. False if degenerate.
bool fit_plane(const std::vector<Eigen::Vector3d>& m, const std::vector<double>& w,
               InverseDepthPlane& plane) {
  std::vector<std::size_t> used(m.size());
  std::iota(used.begin(), used.end(), 0);
  for (int pass = 0; pass < 2; ++pass) {
    if (used.size() < 3) {
      return false;
    }
    Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (const std::size_t i : used) {
      normal_matrix += m[i] * m[i].transpose();
      rhs += w[i] * m[i];
    }
    const Eigen::LDLT<Eigen::Matrix3d> solver(normal_matrix);
    if (solver.info() != Eigen::Success || solver.rcond() < 1e-12) {
      return false;
    }
    plane.v = solver.solve(rhs);
    if (pass == 1) {
      break;
    }
    std::vector<double> residuals;
    for (const std::size_t i : used) {
      residuals.push_back(std::abs(plane.v.dot(m[i]) - w[i]));
    }
    const double sigma = 1.4826 * detail::median(residuals);
    std::vector<std::size_t> inliers;
    for (const std::size_t i : used) {
      if (std::abs(plane.v.dot(m[i]) - w[i]) <= 3.0 * sigma + 1e-12) {
        inliers.push_back(i);
      }
    }
    used.swap(inliers);
  }
  return plane.v.allFinite() && plane.v.norm() > 0.0;
}

/// The marker's image: the corner quadrilateral shrunk by 10 % about its centre (edges mix the
/// marker with what is around it); its pixels with depth as normalised image points and inverse
/// depths.
void marker_samples(const hardware::RgbdFrame& frame, const std::array<Eigen::Vector2d, 4>& corners,
                    std::vector<Eigen::Vector3d>& m, std::vector<double>& w) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& c : corners) {
    centre += 0.25 * c;
  }
  std::vector<cv::Point> quad;
  for (const auto& c : corners) {
    const Eigen::Vector2d p = centre + 0.9 * (c - centre);
    quad.emplace_back(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
  }
  const cv::Rect box =
      cv::boundingRect(quad) & cv::Rect(0, 0, static_cast<int>(frame.intrinsics.width),
                                        static_cast<int>(frame.intrinsics.height));
  if (box.empty()) {
    return;
  }
  cv::Mat inside = cv::Mat::zeros(box.size(), CV_8U);
  for (auto& p : quad) {
    p -= box.tl();
  }
  cv::fillConvexPoly(inside, quad, cv::Scalar(255));
  for (int v = 0; v < box.height; ++v) {
    for (int u = 0; u < box.width; ++u) {
      if (inside.at<std::uint8_t>(v, u) == 0) {
        continue;
      }
      if (const double z = detail::depth_at(frame, box.x + u, box.y + v); z > 0.0) {
        m.push_back(deproject(frame.intrinsics, {box.x + u, box.y + v}, 1.0));
        w.push_back(1.0 / z);
      }
    }
  }
}

/// Refines a detection with the depth image: the corner rays meet the plane fitted to the
/// marker's depth points. False (detection unchanged) if there are too few points.
bool refine_with_depth(const hardware::RgbdFrame& frame, const ArucoParams& params,
                       ArucoDetection& det) {
  std::vector<Eigen::Vector3d> m;
  std::vector<double> w;
  marker_samples(frame, det.corners, m, w);
  InverseDepthPlane plane;
  if (static_cast<int>(m.size()) < params.min_depth_samples || !fit_plane(m, w, plane)) {
    return false;
  }
  std::array<Eigen::Vector3d, 4> corners;
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d ray = deproject(frame.intrinsics, det.corners[i], 1.0);
    if (plane.v.dot(ray) < 1e-6) {
      return false;  // the ray runs along the plane or meets it behind the camera
    }
    corners[i] = plane.on_ray(ray);
  }
  det.optical_T_marker = marker_frame(corners);
  det.measured_size = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    det.measured_size += 0.25 * (corners[(i + 1) % 4] - corners[i]).norm();
  }
  return true;
}

}  // namespace

Eigen::Isometry3d marker_frame(const std::array<Eigen::Vector3d, 4>& c) {
  // Seen from the front with x right and y up: top-left, top-right, bottom-right, bottom-left.
  const Eigen::Vector3d normal = (c[3] - c[1]).cross(c[2] - c[0]);
  const Eigen::Vector3d along_x = (c[1] - c[0]) + (c[2] - c[3]);
  const Eigen::Vector3d along_y = (c[0] - c[3]) + (c[1] - c[2]);
  const double scale = std::max(along_x.squaredNorm(), along_y.squaredNorm());
  if (!(scale > 0.0) || normal.norm() < 1e-9 * scale) {
    throw DrillError("marker frame: the four corners are coincident or collinear");
  }
  const Eigen::Vector3d z = normal.normalized();
  const Eigen::Vector3d x0 = (along_x - along_x.dot(z) * z).normalized();
  const Eigen::Vector3d y0 = (along_y - along_y.dot(z) * z).normalized();
  // The mean of the x the top and bottom edges give and the x the left and right edges give.
  const Eigen::Vector3d x = (x0 + y0.cross(z)).normalized();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear().col(0) = x;
  t.linear().col(1) = z.cross(x);
  t.linear().col(2) = z;
  t.translation() = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  return t;
}

std::vector<ArucoDetection> detect_aruco(const hardware::RgbdFrame& frame,
                                         const ArucoParams& params) {
  const cv::Ptr<cv::aruco::Dictionary> dict = dictionary(params.dictionary);
  if (!(std::isfinite(params.marker_size) && params.marker_size > 0.0)) {
    throw DrillError("ArUco detection: marker_size " + std::to_string(params.marker_size) +
                     " m must be > 0");
  }
  check_frame(frame);
  const auto& k = frame.intrinsics;
  const cv::Mat rgb(static_cast<int>(k.height), static_cast<int>(k.width), CV_8UC3,
                    const_cast<std::uint8_t*>(frame.rgb.data()));
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  auto detector = cv::aruco::DetectorParameters::create();
  detector->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> found;
  cv::aruco::detectMarkers(grey, dict, found, ids, detector);

  const double h = 0.5 * params.marker_size;
  // IPPE_SQUARE's required order: the corners of the marker frame (x right, y up, z out).
  const std::vector<cv::Point3d> object{{-h, h, 0.0}, {h, h, 0.0}, {h, -h, 0.0}, {-h, -h, 0.0}};
  const cv::Matx33d camera(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0);
  const cv::Mat no_distortion = cv::Mat::zeros(1, 5, CV_64F);
  std::vector<ArucoDetection> out;
  for (std::size_t m = 0; m < ids.size(); ++m) {
    ArucoDetection det;
    det.id = ids[m];
    det.dictionary = params.dictionary;
    std::vector<cv::Point2d> image;
    for (std::size_t i = 0; i < 4; ++i) {
      det.corners[i] = {found[m][i].x, found[m][i].y};
      image.emplace_back(found[m][i].x, found[m][i].y);
    }
    cv::Vec3d rvec, tvec;
    if (!cv::solvePnP(object, image, camera, no_distortion, rvec, tvec, false,
                      cv::SOLVEPNP_IPPE_SQUARE)) {
      continue;
    }
    det.pnp = pose(rvec, tvec);
    std::vector<cv::Point2d> reprojected;
    cv::projectPoints(object, rvec, tvec, camera, no_distortion, reprojected);
    double squared = 0.0;
    for (std::size_t i = 0; i < 4; ++i) {
      const cv::Point2d e = reprojected[i] - image[i];
      squared += e.dot(e);
    }
    det.reprojection_error = std::sqrt(squared / 4.0);
    det.optical_T_marker = det.pnp;
    det.depth_refined = params.refine_with_depth && refine_with_depth(frame, params, det);
    out.push_back(det);
  }
  std::sort(out.begin(), out.end(),
            [](const ArucoDetection& a, const ArucoDetection& b) { return a.id < b.id; });
  return out;
}

}  // namespace concert::drill
