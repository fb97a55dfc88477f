#include "drill/area_detection.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "drill/patterns.hpp"
#include "drill/perception.hpp"

namespace concert::drill {
namespace {

// A mark further than this in front of or behind the area's plane is not on its wall [m].
constexpr double kOffPlane = 0.05;

std::string fixed(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

Eigen::Vector3d up_in(const CameraView& view) {
  return view.world_T_optical.linear().transpose() * Eigen::Vector3d::UnitZ();
}

// Distance of a world point from the area's centre within its plane, or infinity when it is
// off the plane.
double in_area(const ResolvedArea& area, const Eigen::Vector3d& p) {
  const Eigen::Vector3d local = area.frame.inverse() * p;
  if (std::abs(local.z()) > kOffPlane) return INFINITY;
  return local.head<2>().norm();
}

}  // namespace

double area_radius(double distance, double fov) { return distance * std::tan(0.5 * fov); }

double smaller_fov(const hardware::CameraIntrinsics& k) {
  return 2.0 * std::min(std::atan(0.5 * k.width / k.fx), std::atan(0.5 * k.height / k.fy));
}

double any_roll_distance(double radius, double fov) { return radius / std::tan(0.45 * fov); }

double marker_look_radius(double marker_size, double drift) {
  return std::sqrt(0.5) * marker_size + drift;
}

bool in_view(const CameraView& view, const Eigen::Vector3d& point) {
  const Eigen::Vector3d p = view.world_T_optical.inverse() * point;
  if (p.z() <= 0.0) return false;
  const Eigen::Vector2d px = project(view.frame->intrinsics, p);
  return px.x() >= 0.0 && px.y() >= 0.0 && px.x() <= view.frame->intrinsics.width - 1.0 &&
         px.y() <= view.frame->intrinsics.height - 1.0;
}

ResolvedArea provisional_area(const Eigen::Vector3d& point, const Eigen::Vector3d& viewer) {
  Eigen::Vector3d z = viewer - point;
  z.z() = 0.0;
  if (z.norm() < 1e-6) z = Eigen::Vector3d::UnitX();
  z.normalize();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitZ();
  ResolvedArea out;
  out.frame.linear().col(0) = y.cross(z);
  out.frame.linear().col(1) = y;
  out.frame.linear().col(2) = z;
  out.frame.translation() = point;
  return out;
}

ResolvedArea locate_area(const AreaSpec& area, const CameraView& view) {
  const hardware::RgbdFrame& frame = *view.frame;
  const Eigen::Vector3d up = up_in(view);
  ResolvedArea out;
  try {
    if (area.pixel) {
      out.frame = view.world_T_optical * area_frame_at(frame, *area.pixel, up);
    } else if (area.point) {
      if (!in_view(view, *area.point)) {
        throw DrillError("point " + fixed(*area.point) + " is outside the drill camera's view");
      }
      const Eigen::Vector3d p = view.world_T_optical.inverse() * *area.point;
      try {
        out.frame = view.world_T_optical * area_frame_at(frame, p, up);
      } catch (const DrillError&) {
        // No surface near the point itself: it was located from afar, or the base's odometry
        // drifted over the approach (on the demo the camera can find no wall within 7 cm of
        // it). The surface along the point's line of sight is taken instead; if none, the
        // first reason.
        std::optional<Eigen::Isometry3d> along;
        try {
          along = area_frame_at(frame, project(frame.intrinsics, p), up);
        } catch (const DrillError&) {
        }
        if (!along) throw;
        out.frame = view.world_T_optical * *along;
      }
    } else {
      throw DrillError("has neither a point nor a pixel to locate it in the camera's view");
    }
  } catch (const DrillError& e) {
    throw DrillError("area '" + area.name + "': " + e.what());
  }
  return out;
}

std::vector<DrillPoint> find_holes(const AreaSpec& area, const ResolvedArea& located,
                                   const CameraView& view, const PatternTable& patterns,
                                   double radius) {
  const hardware::RgbdFrame& frame = *view.frame;
  const Eigen::Vector3d up = up_in(view);
  std::vector<DrillPoint> points;
  std::ostringstream where;
  where.setf(std::ios::fixed);
  where.precision(2);
  where << " within " << radius << " m of the area's centre " << fixed(located.frame.translation());
  try {
    if (area.marks == MarkKind::kBlobs) {
      const std::vector<Blob> blobs = detect_blobs(frame);
      std::vector<std::pair<double, const Blob*>> near;
      for (const Blob& b : blobs) {
        const double d = in_area(located, view.world_T_optical * b.position);
        if (d <= radius) near.emplace_back(d, &b);
      }
      if (near.empty()) {
        throw DrillError("no blue blob visible" + where.str() + " (" +
                         std::to_string(blobs.size()) + " elsewhere in the image)");
      }
      std::sort(near.begin(), near.end(),
                [](const auto& a, const auto& b) { return a.first < b.first; });
      for (std::size_t i = 0; i < near.size(); ++i) {
        DrillPoint p;
        p.frame = view.world_T_optical * area_frame(surface_at(frame, near[i].second->pixel), up);
        p.label = "blob " + std::to_string(i + 1);
        p.servo = true;
        points.push_back(p);
      }
      return points;
    }
    ArucoParams params;
    params.dictionary = patterns.dictionary();
    params.marker_size = patterns.marker_size();
    const std::vector<ArucoDetection> markers = detect_aruco(frame, params);
    const ArucoDetection* best = nullptr;
    double best_d = INFINITY;
    for (const ArucoDetection& m : markers) {
      const double d = in_area(located, view.world_T_optical * m.optical_T_marker.translation());
      if (d <= radius && d < best_d) {
        best = &m;
        best_d = d;
      }
    }
    if (best == nullptr) {
      throw DrillError("no ArUco marker (" + params.dictionary + ") visible" + where.str() + " (" +
                       std::to_string(markers.size()) + " elsewhere in the image)");
    }
    const HolePattern* pattern = patterns.find(best->id);
    if (pattern == nullptr) {
      throw DrillError(
          "ArUco marker " + std::to_string(best->id) + " has no hole pattern in '" +
          (patterns.source().empty() ? std::string("the pattern table") : patterns.source()) + "'");
    }
    const std::vector<Eigen::Isometry3d> holes =
        pattern_holes(view.world_T_optical * best->optical_T_marker, *pattern);
    for (std::size_t i = 0; i < holes.size(); ++i) {
      DrillPoint p;
      p.frame = holes[i];
      p.label = "aruco " + std::to_string(best->id) + " hole " + std::to_string(i + 1);
      p.servo = false;
      p.marker = best->id;
      p.pattern_index = static_cast<int>(i);
      points.push_back(p);
    }
  } catch (const DrillError& e) {
    throw DrillError("area '" + area.name + "': " + e.what());
  }
  return points;
}

std::optional<Eigen::Isometry3d> reanchor(const CameraView& view, const DrillPoint& hole,
                                          const PatternTable& patterns, double max_distance) {
  const hardware::RgbdFrame& frame = *view.frame;
  const Eigen::Vector3d up = up_in(view);
  const Eigen::Vector3d predicted = hole.frame.translation();
  try {
    if (hole.marker < 0) {
      const Blob* best = nullptr;
      double best_d = max_distance;
      const std::vector<Blob> blobs = detect_blobs(frame);
      for (const Blob& b : blobs) {
        const double d = (view.world_T_optical * b.position - predicted).norm();
        if (d <= best_d) {
          best_d = d;
          best = &b;
        }
      }
      if (best != nullptr)
        return view.world_T_optical * area_frame(surface_at(frame, best->pixel), up);
    } else if (const std::optional<Eigen::Isometry3d> marker = find_marker(
                   view, hole.marker, marker_of(hole, patterns).value_or(hole.frame).translation(),
                   patterns)) {
      const std::optional<Eigen::Isometry3d> seen = hole_of_seen_marker(hole, *marker, patterns);
      if (seen && (seen->translation() - predicted).norm() <= max_distance) return seen;
    }
    if (!in_view(view, predicted)) return std::nullopt;
    // The wall under the predicted position: its normal, and the position moved onto it.
    Eigen::Isometry3d out =
        view.world_T_optical *
        area_frame_at(frame, Eigen::Vector3d(view.world_T_optical.inverse() * predicted), up);
    const Eigen::Vector3d n = out.linear().col(2);
    out.translation() = predicted + n * n.dot(out.translation() - predicted);
    return out;
  } catch (const DrillError&) {
    return std::nullopt;  // no depth there, too few points: the prediction stands
  }
}

std::optional<Eigen::Isometry3d> hole_of(const DrillPoint& hole,
                                         const Eigen::Isometry3d& world_T_marker,
                                         const PatternTable& patterns) {
  const HolePattern* pattern = hole.marker < 0 ? nullptr : patterns.find(hole.marker);
  if (pattern == nullptr || hole.pattern_index < 0) return std::nullopt;
  const std::vector<Eigen::Isometry3d> holes = pattern_holes(world_T_marker, *pattern);
  const auto i = static_cast<std::size_t>(hole.pattern_index);
  if (i >= holes.size()) return std::nullopt;
  return holes[i];
}

std::optional<Eigen::Isometry3d> marker_of(const DrillPoint& hole, const PatternTable& patterns) {
  // The pattern laid on a marker at the origin gives marker_T_hole.
  const std::optional<Eigen::Isometry3d> marker_T_hole =
      hole_of(hole, Eigen::Isometry3d::Identity(), patterns);
  if (!marker_T_hole) return std::nullopt;
  return hole.frame * marker_T_hole->inverse();
}

std::optional<Eigen::Isometry3d> hole_of_seen_marker(const DrillPoint& hole,
                                                     const Eigen::Isometry3d& seen,
                                                     const PatternTable& patterns) {
  std::optional<Eigen::Isometry3d> marker = marker_of(hole, patterns);
  if (!marker) return std::nullopt;
  marker->translation() = seen.translation();
  return hole_of(hole, *marker, patterns);
}

std::optional<Eigen::Isometry3d> find_marker(const CameraView& view, int id,
                                             const Eigen::Vector3d& near,
                                             const PatternTable& patterns) {
  ArucoParams params;
  params.dictionary = patterns.dictionary();
  params.marker_size = patterns.marker_size();
  // A wall can carry several markers of one id (scenario 3's wall: four of id 0, one pattern
  // each): the one nearest where this one was expected, not the first the detector lists.
  std::optional<Eigen::Isometry3d> best;
  for (const ArucoDetection& m : detect_aruco(*view.frame, params)) {
    if (m.id != id) continue;
    const Eigen::Isometry3d world_T_marker = view.world_T_optical * m.optical_T_marker;
    if (!best || (world_T_marker.translation() - near).norm() < (best->translation() - near).norm())
      best = world_T_marker;
  }
  return best;
}

std::optional<AreaShift> blob_shift(const CameraView& view, const std::vector<DrillPoint>& area_points,
                                    double tolerance, double max_shift, double max_set_shift) {
  std::vector<Eigen::Vector3d> seen;
  for (const Blob& b : detect_blobs(*view.frame)) seen.push_back(view.world_T_optical * b.position);
  // Every seen blob taken for every predicted one is a candidate shift; it scores the predicted
  // blobs it lays onto seen ones.
  std::vector<AreaShift> candidates;
  const double longest = std::max(max_shift, max_set_shift);
  for (const Eigen::Vector3d& s : seen) {
    for (const DrillPoint& p : area_points) {
      if (p.marker >= 0) continue;
      const Eigen::Vector3d shift = s - p.frame.translation();
      // Unbounded, the neighbour 0.1 m away seen alone would score like the target's own blob,
      // and the hole would be drilled there, 0.1 m off.
      if (shift.norm() > longest) continue;
      int score = 0;
      for (const DrillPoint& o : area_points) {
        if (o.marker >= 0) continue;
        const Eigen::Vector3d moved = o.frame.translation() + shift;
        if (std::any_of(seen.begin(), seen.end(),
                        [&](const Eigen::Vector3d& v) { return (v - moved).norm() <= tolerance; }))
          ++score;
      }
      // Beyond max_shift only a set of blobs is taken for the area.
      if (shift.norm() <= max_shift || score >= 2) candidates.push_back({shift, score});
    }
  }
  // The best explanation within max_shift, unless a longer shift lays more blobs onto seen ones
  // (the set beyond the window); ties go to the smallest shift.
  const auto best_of = [&](bool within) {
    const AreaShift* best = nullptr;
    for (const AreaShift& c : candidates) {
      if (within && c.by.norm() > max_shift) continue;
      if (best == nullptr || c.blobs > best->blobs ||
          (c.blobs == best->blobs && c.by.norm() < best->by.norm()))
        best = &c;
    }
    return best;
  };
  const AreaShift* best = best_of(true);
  bool within = true;
  if (const AreaShift* any = best_of(false); any != nullptr && (best == nullptr || any->blobs > best->blobs)) {
    best = any;
    within = false;
  }
  if (best == nullptr) return std::nullopt;
  // Another explanation as good as the best one: one blob seen alone within the window of two
  // predicted ones (a re-measure some 5 cm off can take a blob for its neighbour this way, and
  // the hole would then be cut on the neighbour).
  for (const AreaShift& c : candidates) {
    if (within && c.by.norm() > max_shift) continue;
    if (c.blobs == best->blobs && (c.by - best->by).norm() > tolerance) return std::nullopt;
  }
  return *best;
}

std::optional<BlobPairView> blob_pair_view(const DrillPoint& hole, const std::vector<DrillPoint>& area_points,
                                           double drift) {
  const Eigen::Vector3d at = hole.frame.translation();
  const DrillPoint* nearest = nullptr;
  for (const DrillPoint& p : area_points) {
    if (p.marker >= 0 || p.label == hole.label) continue;
    if (nearest == nullptr ||
        (p.frame.translation() - at).norm() < (nearest->frame.translation() - at).norm())
      nearest = &p;
  }
  if (nearest == nullptr) return std::nullopt;
  return BlobPairView{0.5 * (at + nearest->frame.translation()),
                      0.5 * (nearest->frame.translation() - at).norm() + drift};
}

std::optional<Eigen::Isometry3d> track_blob(const CameraView& view, const Eigen::Isometry3d& hole,
                                            double max_distance) {
  std::optional<Eigen::Isometry3d> best;
  double best_d = max_distance;
  for (const Blob& b : detect_blobs(*view.frame)) {
    const Eigen::Vector3d p = view.world_T_optical * b.position;
    const double d = (p - hole.translation()).norm();
    if (d <= best_d) {
      best_d = d;
      Eigen::Isometry3d seen = hole;
      // On the hole's plane (the normal estimated when the area was detected): the blob's
      // centre moves the hole within the surface, not along the normal.
      const Eigen::Vector3d n = hole.linear().col(2);
      seen.translation() = p - n * n.dot(p - hole.translation());
      best = seen;
    }
  }
  return best;
}

}  // namespace concert::drill
