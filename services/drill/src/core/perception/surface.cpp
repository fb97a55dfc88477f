// The surface normal at a picked point and the drilling area frame (PCL). The only source that
// includes PCL: its headers compile slowly.
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <cmath>
#include <cstdio>

#include "drill/perception.hpp"
#include "frame_access.hpp"

namespace concert::drill {

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

void check_params(const SurfaceParams& p) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(p.voxel) || !positive(p.normal_radius) || !positive(p.average_radius) ||
      p.min_normals < 1) {
    throw DrillError(
        "surface normal: voxel, normal_radius and average_radius must be > 0 m and "
        "min_normals >= 1");
  }
}

/// The frame's depth points within `radius` of `centre` (optical frame) [m].
Cloud::Ptr points_near(const hardware::RgbdFrame& frame, const Eigen::Vector3d& centre,
                       double radius) {
  auto cloud = std::make_shared<Cloud>();
  const auto& k = frame.intrinsics;
  for (int v = 0; v < static_cast<int>(k.height); ++v) {
    for (int u = 0; u < static_cast<int>(k.width); ++u) {
      const double z = detail::depth_at(frame, u, v);
      if (z <= 0.0) {
        continue;
      }
      const Eigen::Vector3d p = deproject(k, {u, v}, z);
      if ((p - centre).squaredNorm() <= radius * radius) {
        cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                       static_cast<float>(p.z())));
      }
    }
  }
  return cloud;
}

/// The plane of the surface near `seed`: the centroid of the downsampled points within
/// average_radius and the mean of their normals (towards the camera).
struct Plane {
  Eigen::Vector3d centroid;
  Eigen::Vector3d normal;
  int normals{0};
};

Plane plane_near(const hardware::RgbdFrame& frame, const Eigen::Vector3d& seed,
                 const SurfaceParams& params, const std::string& where) {
  check_params(params);
  // Normals of points within average_radius need their neighbours within normal_radius; one
  // voxel more for the voxels straddling the boundary.
  const Cloud::Ptr near =
      points_near(frame, seed, params.average_radius + params.normal_radius + params.voxel);
  auto down = std::make_shared<Cloud>();
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(near);
  const auto leaf = static_cast<float>(params.voxel);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(*down);

  auto indices = std::make_shared<pcl::Indices>();
  for (std::size_t i = 0; i < down->size(); ++i) {
    if (((*down)[i].getVector3fMap().cast<double>() - seed).norm() <= params.average_radius) {
      indices->push_back(static_cast<int>(i));
    }
  }
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
  estimation.setInputCloud(down);
  estimation.setIndices(indices);
  estimation.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
  estimation.setRadiusSearch(params.normal_radius);
  estimation.setViewPoint(0.0f, 0.0f, 0.0f);  // the camera: normals point towards it
  pcl::PointCloud<pcl::Normal> normals;
  estimation.compute(normals);

  Plane plane{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0};
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const Eigen::Vector3d n = normals[i].getNormalVector3fMap().cast<double>();
    if (!n.allFinite()) {
      continue;  // too few neighbours
    }
    plane.normal += n;
    plane.centroid +=
        (*down)[static_cast<std::size_t>((*indices)[i])].getVector3fMap().cast<double>();
    ++plane.normals;
  }
  if (plane.normals < params.min_normals || plane.normal.norm() < 1e-9) {
    detail::fail(frame, "too little surface around " + where + " for a normal (" +
                            std::to_string(plane.normals) + " points with a normal within " +
                            std::to_string(params.average_radius) + " m, need " +
                            std::to_string(params.min_normals) + ")");
  }
  plane.centroid /= plane.normals;
  plane.normal.normalize();
  return plane;
}

std::string describe_point(const char* format, double a, double b, double c = 0.0) {
  char text[96];
  std::snprintf(text, sizeof(text), format, a, b, c);
  return text;
}

}  // namespace

SurfacePatch surface_at(const hardware::RgbdFrame& frame, const Eigen::Vector2d& pixel,
                        const SurfaceParams& params) {
  const Eigen::Vector3d seed = point_at_pixel(frame, pixel, 5.0);
  const Plane plane =
      plane_near(frame, seed, params, describe_point("pixel (%.1f, %.1f)", pixel.x(), pixel.y()));
  const Eigen::Vector3d ray = deproject(frame.intrinsics, pixel, 1.0);
  const double along = plane.normal.dot(ray);
  SurfacePatch patch;
  patch.normal = plane.normal;
  patch.normals = plane.normals;
  // Where the ray meets the plane; the seed itself if the ray grazes it.
  patch.point = std::abs(along) > 1e-6
                    ? Eigen::Vector3d(plane.normal.dot(plane.centroid) / along * ray)
                    : seed;
  return patch;
}

SurfacePatch surface_at(const hardware::RgbdFrame& frame, const Eigen::Vector3d& point,
                        const SurfaceParams& params) {
  check_frame(frame);
  if (!point.allFinite()) {
    detail::fail(frame, "the point to find the surface at is not finite");
  }
  const Plane plane =
      plane_near(frame, point, params,
                 describe_point("point (%.3f, %.3f, %.3f) m", point.x(), point.y(), point.z()));
  SurfacePatch patch;
  patch.normal = plane.normal;
  patch.normals = plane.normals;
  patch.point = point - plane.normal.dot(point - plane.centroid) * plane.normal;
  return patch;
}

Eigen::Isometry3d area_frame(const SurfacePatch& patch, const Eigen::Vector3d& up_in_optical) {
  const Eigen::Vector3d z = patch.normal.normalized();
  if (!up_in_optical.allFinite() || up_in_optical.norm() < 1e-9 || !z.allFinite()) {
    throw DrillError("area frame: the up direction and the normal must be non-zero and finite");
  }
  const Eigen::Vector3d across = up_in_optical.normalized().cross(z);
  if (across.norm() < std::sin(M_PI / 180.0)) {
    throw DrillError(
        "area frame: the surface normal is within 1 degree of up (a floor or a "
        "ceiling): no horizontal direction in it");
  }
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear().col(0) = across.normalized();
  t.linear().col(1) = z.cross(t.linear().col(0));
  t.linear().col(2) = z;
  t.translation() = patch.point;
  return t;
}

Eigen::Isometry3d area_frame_at(const hardware::RgbdFrame& frame, const Eigen::Vector2d& pixel,
                                const Eigen::Vector3d& up_in_optical, const SurfaceParams& params) {
  return area_frame(surface_at(frame, pixel, params), up_in_optical);
}

Eigen::Isometry3d area_frame_at(const hardware::RgbdFrame& frame, const Eigen::Vector3d& point,
                                const Eigen::Vector3d& up_in_optical, const SurfaceParams& params) {
  return area_frame(surface_at(frame, point, params), up_in_optical);
}

}  // namespace concert::drill
