#include "planner/sensor_map.hpp"

#include <cmath>
#include <exception>
#include <sstream>

namespace concert::planner {
namespace {

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

bool finite(const Eigen::Isometry3d& t) { return t.matrix().allFinite(); }

}  // namespace

SensorMapper::SensorMapper(std::shared_ptr<const PlanningModel> model, const Params& params)
    : model_(std::move(model)), params_(params) {
  if (!model_) throw PlannerError("sensor map: no planning model");
  if (!(params.sensor_max_range > 0.0))
    throw PlannerError("sensor map: sensor_max_range must be > 0, got " +
                       num(params.sensor_max_range));
  if (!(params.sensor_self_padding >= 0.0))
    throw PlannerError("sensor map: sensor_self_padding must be >= 0, got " +
                       num(params.sensor_self_padding));
  if (!(params.sensor_floor_band >= 0.0))
    throw PlannerError("sensor map: sensor_floor_band must be >= 0, got " +
                       num(params.sensor_floor_band));
  if (params.sensor_depth_stride < 1)
    throw PlannerError("sensor map: sensor_depth_stride must be >= 1, got " +
                       std::to_string(params.sensor_depth_stride));
  if (!(params.sensor_depth_min_valid > 0.0 && params.sensor_depth_min_valid <= 1.0)) {
    throw PlannerError("sensor map: sensor_depth_min_valid must be in (0, 1], got " +
                       num(params.sensor_depth_min_valid));
  }
}

void SensorMapper::check_q(const Eigen::VectorXd& q_full, const std::string& what) const {
  if (q_full.size() != model_->full_dof()) {
    throw PlannerError(what + ": joint vector has " + std::to_string(q_full.size()) +
                       " values, the model " + std::to_string(model_->full_dof()));
  }
  if (!q_full.allFinite()) throw PlannerError(what + ": joint vector is not finite");
}

Eigen::Isometry3d SensorMapper::sensor_pose(const Eigen::VectorXd& q_full,
                                            const std::string& frame) const {
  check_q(q_full, "sensor frame '" + frame + "'");
  return model_->link_pose(q_full, frame);
}

std::vector<SensorMapper::PaddedShape> SensorMapper::padded_shapes(
    const std::vector<Eigen::Isometry3d>& link_poses) const {
  const double pad = params_.sensor_self_padding;
  const auto& links = model_->links();
  std::vector<PaddedShape> out;
  for (std::size_t i = 0; i < links.size() && i < link_poses.size(); ++i) {
    for (const LinkShape& s : links[i].shapes) {
      PaddedShape p;
      p.type = s.type;
      const Eigen::Isometry3d map_T_shape = link_poses[i] * s.origin;
      p.shape_T_map = map_T_shape.inverse();
      p.centre = map_T_shape.translation();
      // Primitives are centred on their origin (URDF); half extents grown by the padding.
      switch (s.type) {
        case LinkShape::Type::kBox:
          p.half = 0.5 * s.size + Eigen::Vector3d::Constant(pad);
          break;
        case LinkShape::Type::kCylinder:
          p.half = Eigen::Vector3d(s.size.x() + pad, s.size.x() + pad, 0.5 * s.size.z() + pad);
          break;
        case LinkShape::Type::kSphere:
          p.half = Eigen::Vector3d::Constant(s.size.x() + pad);
          break;
      }
      p.radius = p.type == LinkShape::Type::kSphere ? p.half.x() : p.half.norm();
      out.push_back(p);
    }
  }
  return out;
}

bool SensorMapper::inside(const std::vector<PaddedShape>& shapes, const Eigen::Vector3d& p) {
  for (const PaddedShape& s : shapes) {
    if ((p - s.centre).squaredNorm() > s.radius * s.radius)
      continue;  // outside its bounding sphere
    const Eigen::Vector3d l = s.shape_T_map * p;
    switch (s.type) {
      case LinkShape::Type::kBox:
        if ((l.cwiseAbs().array() <= s.half.array()).all()) return true;
        break;
      case LinkShape::Type::kCylinder:
        if (l.head<2>().norm() <= s.half.x() && std::abs(l.z()) <= s.half.z()) return true;
        break;
      case LinkShape::Type::kSphere:
        return true;  // within the sphere's radius
    }
  }
  return false;
}

bool SensorMapper::on_robot(const Eigen::Vector3d& p,
                            const std::vector<Eigen::Isometry3d>& link_poses) const {
  return inside(padded_shapes(link_poses), p);
}

SensorRays SensorMapper::sort(const Eigen::Vector3d& origin,
                              const std::vector<Eigen::Vector3d>& ends,
                              const Eigen::VectorXd& q_full) const {
  std::vector<Eigen::Isometry3d> poses;
  model_->link_poses(q_full, poses);
  const std::vector<PaddedShape> robot = padded_shapes(poses);
  SensorRays out;
  out.rays.origin = origin;
  SensorMapStats& stats = out.stats;
  stats.returns = ends.size();
  std::vector<Eigen::Vector3d>& hits = out.rays.hits;
  std::vector<Eigen::Vector3d>& clears = out.rays.clears;
  hits.reserve(ends.size());
  const double floor_top = params_.floor_height + params_.sensor_floor_band;
  for (const Eigen::Vector3d& end : ends) {
    const Eigen::Vector3d ray = end - origin;
    const double range = ray.norm();
    if (range > params_.sensor_max_range) {
      clears.push_back(origin + ray * (params_.sensor_max_range / range));
      stats.cut += 1;
    } else if (inside(robot, end)) {
      stats.self += 1;
    } else if (end.z() < floor_top) {
      clears.push_back(end);
      stats.floor += 1;
    } else {
      hits.push_back(end);
      stats.occupied += 1;
    }
  }
  return out;
}

SensorMapStats SensorMapper::insert_lidar(Environment& environment, const hardware::LidarScan& scan,
                                          const Eigen::Isometry3d& map_T_sensor,
                                          const Eigen::VectorXd& q_full) const {
  const SensorRays r = lidar_rays(scan, map_T_sensor, q_full);
  environment.insert_rays({r.rays});
  return r.stats;
}

SensorMapStats SensorMapper::insert_depth(Environment& environment,
                                          const std::vector<hardware::RgbdFrame>& frames,
                                          const Eigen::Isometry3d& map_T_optical,
                                          const Eigen::VectorXd& q_full) const {
  const SensorRays r = depth_rays(frames, map_T_optical, q_full);
  environment.insert_rays({r.rays});
  return r.stats;
}

SensorRays SensorMapper::lidar_rays(const hardware::LidarScan& scan,
                                    const Eigen::Isometry3d& map_T_sensor,
                                    const Eigen::VectorXd& q_full) const {
  const std::string what = "lidar '" + scan.sensor + "' (frame '" + scan.frame + "')";
  const std::size_t rings = scan.elevations.size();
  if (rings == 0) throw PlannerError(what + ": elevations: no rings");
  if (scan.columns == 0) throw PlannerError(what + ": columns: 0");
  if (scan.ranges.size() != rings * scan.columns) {
    throw PlannerError(what + ": ranges has " + std::to_string(scan.ranges.size()) +
                       " values, rings x columns = " + std::to_string(rings) + " x " +
                       std::to_string(scan.columns) + " = " + std::to_string(rings * scan.columns));
  }
  if (!std::isfinite(scan.azimuth_min) || !std::isfinite(scan.azimuth_increment)) {
    throw PlannerError(what + ": azimuth_min and azimuth_increment must be finite");
  }
  for (std::size_t r = 0; r < rings; ++r) {
    if (!std::isfinite(scan.elevations[r]))
      throw PlannerError(what + ": elevation of ring " + std::to_string(r) + " is not finite");
  }
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    if (!std::isfinite(scan.ranges[i]) || scan.ranges[i] < 0.0F) {
      throw PlannerError(what + ": range " + std::to_string(i) + " (ring " +
                         std::to_string(i / scan.columns) + ", column " +
                         std::to_string(i % scan.columns) + ") is " + num(scan.ranges[i]) +
                         ", expected finite and >= 0");
    }
  }
  if (!finite(map_T_sensor)) throw PlannerError(what + ": sensor pose is not finite");
  check_q(q_full, what);

  std::vector<Eigen::Vector3d> ends;
  ends.reserve(scan.ranges.size());
  std::size_t no_return = 0;
  std::vector<double> ca(scan.columns), sa(scan.columns);
  for (std::uint32_t c = 0; c < scan.columns; ++c) {
    const double a = scan.azimuth_min + scan.azimuth_increment * c;
    ca[c] = std::cos(a);
    sa[c] = std::sin(a);
  }
  for (std::size_t r = 0; r < rings; ++r) {
    const double ce = std::cos(scan.elevations[r]), se = std::sin(scan.elevations[r]);
    for (std::uint32_t c = 0; c < scan.columns; ++c) {
      const double range = scan.ranges[r * scan.columns + c];
      if (range <= 0.0 || range < scan.range_min) {
        no_return += 1;
        continue;
      }
      ends.push_back(map_T_sensor * (range * Eigen::Vector3d(ce * ca[c], ce * sa[c], se)));
    }
  }
  SensorRays out = sort(map_T_sensor.translation(), ends, q_full);
  out.stats.no_return = no_return;
  return out;
}

SensorRays SensorMapper::depth_rays(const std::vector<hardware::RgbdFrame>& frames,
                                    const Eigen::Isometry3d& map_T_optical,
                                    const Eigen::VectorXd& q_full) const {
  if (frames.empty()) throw PlannerError("depth: no frames");
  const hardware::RgbdFrame& first = frames.front();
  const std::string what = "camera '" + first.sensor + "' (frame '" + first.frame + "')";
  const hardware::CameraIntrinsics& k = first.intrinsics;
  if (k.width == 0 || k.height == 0) throw PlannerError(what + ": intrinsics: image size is 0");
  if (!(k.fx > 0.0) || !(k.fy > 0.0) || !std::isfinite(k.fx) || !std::isfinite(k.fy) ||
      !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    throw PlannerError(what + ": intrinsics: fx, fy must be finite and > 0, cx, cy finite");
  }
  const std::size_t pixels = static_cast<std::size_t>(k.width) * k.height;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const hardware::RgbdFrame& fr = frames[f];
    const std::string which = what + ": frame " + std::to_string(f);
    if (fr.sensor != first.sensor || !(fr.intrinsics == k))
      throw PlannerError(which + ": another camera or other intrinsics than frame 0");
    if (fr.depth.size() != pixels) {
      throw PlannerError(which + ": depth has " + std::to_string(fr.depth.size()) +
                         " values, width x height = " + std::to_string(pixels));
    }
    if (!(fr.depth_scale > 0.0) || !std::isfinite(fr.depth_scale))
      throw PlannerError(which + ": depth_scale must be finite and > 0");
  }
  if (!finite(map_T_optical)) throw PlannerError(what + ": sensor pose is not finite");
  check_q(q_full, what);

  const auto needed = static_cast<std::size_t>(
      std::ceil(params_.sensor_depth_min_valid * static_cast<double>(frames.size()) - 1e-9));
  const auto stride = static_cast<std::uint32_t>(params_.sensor_depth_stride);
  std::vector<Eigen::Vector3d> ends;
  std::size_t no_return = 0;
  for (std::uint32_t v = 0; v < k.height; v += stride) {
    for (std::uint32_t u = 0; u < k.width; u += stride) {
      const std::size_t i = static_cast<std::size_t>(v) * k.width + u;
      double sum = 0.0;
      std::size_t count = 0;
      for (const hardware::RgbdFrame& fr : frames) {
        if (fr.depth[i] == 0) continue;
        sum += fr.depth[i] * fr.depth_scale;
        count += 1;
      }
      if (count == 0 || count < needed) {
        no_return += 1;
        continue;
      }
      const double z = sum / static_cast<double>(count);
      const Eigen::Vector3d p((u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z);
      ends.push_back(map_T_optical * p);
    }
  }
  SensorRays out = sort(map_T_optical.translation(), ends, q_full);
  out.stats.no_return = no_return;
  return out;
}

BatchRays SensorMapper::batch_rays(const SensorBatch& batch, const Eigen::VectorXd& q_full) const {
  BatchRays out;
  auto take = [&](SensorRays r, std::string used) {
    out.stats.occupied += r.stats.occupied;
    out.stats.self += r.stats.self;
    out.stats.floor += r.stats.floor;
    out.stats.returns += r.stats.returns;
    out.stats.cut += r.stats.cut;
    out.stats.no_return += r.stats.no_return;
    out.bundles.push_back(std::move(r.rays));
    out.used.push_back(std::move(used));
  };
  for (const auto& [name, scan] : batch.scans) {
    try {
      take(lidar_rays(scan, sensor_pose(q_full, scan.frame), q_full), name);
    } catch (const std::exception& e) {
      out.refused.push_back(name + ": " + e.what());
    }
  }
  for (const auto& [name, frames] : batch.depth) {
    if (frames.empty()) continue;
    try {
      take(depth_rays(frames, sensor_pose(q_full, frames.front().frame), q_full),
           name + " (" + std::to_string(frames.size()) + " depth frames averaged)");
    } catch (const std::exception& e) {
      out.refused.push_back(name + ": " + e.what());
    }
  }
  return out;
}

std::string describe(const SensorMapUpdate& u) {
  std::ostringstream line;
  line << "planner: sensor map: used ";
  for (std::size_t i = 0; i < u.rays.used.size(); ++i) line << (i == 0 ? "" : ", ") << u.rays.used[i];
  if (u.rays.used.empty()) line << "nothing";
  line << " in " << std::lround(u.milliseconds) << " ms, " << u.rays.stats.occupied << " hits, " << u.rays.stats.self
       << " on the robot, " << u.rays.stats.floor << " floor; map " << u.occupied_cells << " occupied cells";
  if (u.skipped_moving > 0) line << "; " << u.skipped_moving << " revolutions or frames skipped: the robot moved";
  if (u.skipped_version > 0) {
    line << "; " << u.skipped_version << " skipped: not of model version " << u.model_version << " or no joint state";
  }
  for (const std::string& r : u.rays.refused) line << "; refused " << r;
  return line.str();
}

}  // namespace concert::planner
