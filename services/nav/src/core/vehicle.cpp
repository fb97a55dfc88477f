#include "nav/vehicle.hpp"


#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

namespace concert::nav {

namespace {

using model::ChainRole;
using model::CollisionShape;
using model::RobotModel;

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Outline points of one collision shape on the floor plane: box corners, the end circles of a
// cylinder, the equator of a sphere (circles circumscribed by `segments`-gons, so the hull holds
// the true shape).
void shape_points(const CollisionShape& shape, const Eigen::Isometry3d& base_T_link, int segments,
                  const std::string& link, const std::string& where,
                  std::vector<Eigen::Vector2d>& out) {
  const Eigen::Isometry3d base_T_shape = base_T_link * shape.origin;
  const double grow = 1.0 / std::cos(std::numbers::pi / segments);
  auto circle = [&](const Eigen::Vector3d& centre, const Eigen::Vector3d& u,
                    const Eigen::Vector3d& v, double radius) {
    for (int k = 0; k < segments; ++k) {
      const double a = 2.0 * std::numbers::pi * k / segments;
      const Eigen::Vector3d p = centre + radius * grow * (std::cos(a) * u + std::sin(a) * v);
      out.emplace_back(p.head<2>());
    }
  };
  switch (shape.type) {
    case CollisionShape::Type::kBox:
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d corner(((k & 1) ? 0.5 : -0.5) * shape.size.x(),
                                     ((k & 2) ? 0.5 : -0.5) * shape.size.y(),
                                     ((k & 4) ? 0.5 : -0.5) * shape.size.z());
        out.emplace_back((base_T_shape * corner).head<2>());
      }
      break;
    case CollisionShape::Type::kCylinder: {
      const Eigen::Matrix3d r = base_T_shape.linear();
      for (double end : {-0.5, 0.5}) {
        circle(base_T_shape * Eigen::Vector3d(0, 0, end * shape.size.z()), r.col(0), r.col(1),
               shape.size.x());
      }
      break;
    }
    case CollisionShape::Type::kSphere:
      circle(base_T_shape.translation(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
             shape.size.x());
      break;
    case CollisionShape::Type::kMesh:
      throw VehicleError(where + ": link '" + link + "' has a mesh collision shape ('" +
                         shape.mesh + "'): the footprint needs boxes, cylinders or spheres");
  }
}

// Axis of moving joint `j` in the base frame at `q`.
Eigen::Vector3d axis_in_base(const kinematics::Model& kin, kinematics::Data& data,
                             const Eigen::VectorXd& q, int j) {
  const Eigen::Isometry3d base_T_child =
      kin.relative_pose(data, q, kin.root_link(), kin.joint_child_link(j));
  return (base_T_child.linear() * kin.joint_axis(j)).normalized();
}

double velocity_limit(const RobotModel& model, const std::string& joint) {
  return model.limits().at(joint).velocity;
}

Footprint make_footprint(const RobotModel& model, const Eigen::VectorXd& q_transport,
                         const std::string& posture, const std::vector<mobile_base::Leg>& steering,
                         const VehicleParams& params) {
  const kinematics::Model& kin = model.kinematics();
  kinematics::Data data = kin.make_data();
  // Links moved by a steering joint are swept over its range.
  std::map<std::string, const mobile_base::Leg*> swept_by;
  for (const mobile_base::Leg& leg : steering) {
    for (const std::string& link : kin.subtree_links(leg.steering_index)) swept_by[link] = &leg;
  }
  std::vector<Eigen::Vector2d> points;
  for (const model::Link& link : model.links()) {
    if (link.shapes.empty()) continue;
    const auto leg = swept_by.find(link.name);
    Eigen::VectorXd q = q_transport;
    if (leg == swept_by.end()) {
      const Eigen::Isometry3d base_T_link = kin.relative_pose(data, q, kin.root_link(), link.name);
      for (const CollisionShape& s : link.shapes) {
        shape_points(s, base_T_link, params.circle_segments, link.name, model.where(), points);
      }
      continue;
    }
    const double lower = std::max(leg->second->steering_lower, -std::numbers::pi);
    const double upper = std::min(leg->second->steering_upper, std::numbers::pi);
    const int n = std::max(params.steering_samples, 2);
    for (int k = 0; k < n; ++k) {
      q[leg->second->steering_index] = lower + (upper - lower) * k / (n - 1);
      const Eigen::Isometry3d base_T_link = kin.relative_pose(data, q, kin.root_link(), link.name);
      for (const CollisionShape& s : link.shapes) {
        shape_points(s, base_T_link, params.circle_segments, link.name, model.where(), points);
      }
    }
  }
  Footprint fp;
  fp.posture = posture;
  fp.steering_swept = !steering.empty();
  fp.polygon = convex_hull(std::move(points));
  if (fp.polygon.size() < 3) {
    throw VehicleError(model.where() + ": the collision shapes give no footprint area");
  }
  double inscribed = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < fp.polygon.size(); ++i) {
    const Eigen::Vector2d& a = fp.polygon[i];
    const Eigen::Vector2d& b = fp.polygon[(i + 1) % fp.polygon.size()];
    const double signed_distance = cross2(b - a, -a) / (b - a).norm();  // > 0: origin on the left
    if (signed_distance <= 0.0) {
      throw VehicleError(model.where() + ": the base frame's origin lies outside the footprint");
    }
    inscribed = std::min(inscribed, signed_distance);
    fp.circumscribed_radius = std::max(fp.circumscribed_radius, a.norm());
  }
  fp.inscribed_radius = inscribed;
  return fp;
}

Perception make_perception(const RobotModel& model, const Eigen::VectorXd& q,
                           const VehicleParams& params) {
  const kinematics::Model& kin = model.kinematics();
  kinematics::Data data = kin.make_data();
  Perception p;
  for (const model::SensorFrame& s : model.sensor_frames()) {
    SensorPose pose{s.name, s.frame, kin.relative_pose(data, q, kin.root_link(), s.frame)};
    switch (s.kind) {
      case model::SensorKind::kLidar:
        (params.planar_lidar_modules.contains(s.module_key) ? p.planar_lidars : p.lidars_3d)
            .push_back(std::move(pose));
        break;
      case model::SensorKind::kSonar:
        p.sonars.push_back(std::move(pose));
        break;
      case model::SensorKind::kImu:
        p.imus.push_back(std::move(pose));
        break;
      case model::SensorKind::kCamera:
        p.cameras.push_back(std::move(pose));
        break;
      case model::SensorKind::kForceTorque:
      case model::SensorKind::kOther:
        break;
    }
  }
  return p;
}

}  // namespace

std::string_view to_string(DriveType drive) {
  switch (drive) {
    case DriveType::kOmniSteering:
      return "omni_steering";
    case DriveType::kDifferential:
      return "differential";
  }
  return "unknown";
}

std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (points.size() < 3) return points;
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  std::size_t k = 0;
  auto turn = [&](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return cross2(a - o, b - o);
  };
  for (const Eigen::Vector2d& p : points) {  // lower hull
    while (k >= 2 && turn(hull[k - 2], hull[k - 1], p) <= 1e-12) --k;
    hull[k++] = p;
  }
  const std::size_t lower_size = k + 1;
  for (auto it = points.rbegin() + 1; it != points.rend(); ++it) {  // upper hull
    while (k >= lower_size && turn(hull[k - 2], hull[k - 1], *it) <= 1e-12) --k;
    hull[k++] = *it;
  }
  hull.resize(k - 1);
  return hull;
}

Eigen::VectorXd transport_posture(const RobotModel& model, std::string* posture) {
  if (posture != nullptr) *posture = model.home().empty() ? "q = 0" : "SRDF home";
  return model.home_posture();  // the planner's `plan home` ends on it too
}

VehicleConfig recognise_vehicle(const RobotModel& model, const VehicleParams& params) {
  const std::string where = model.where();
  const kinematics::Model& kin = model.kinematics();
  kinematics::Data data = kin.make_data();

  std::vector<model::Leg> legs;
  try {
    legs = model.legs();
  } catch (const model::ModelError& e) {
    throw VehicleError(e.what());
  }
  if (legs.empty()) {
    std::vector<std::string> chains;
    for (const model::ChainInfo& c : model.chains()) {
      chains.push_back(c.name + " (" + std::string(model::to_string(c.role)) + ")");
    }
    throw VehicleError(where +
                       ": no wheels: a fixed-base arm cannot navigate (no leg chain; chains: " +
                       (chains.empty() ? std::string("none") : join(chains)) + ")");
  }

  std::string posture;
  const Eigen::VectorXd q = transport_posture(model, &posture);

  std::vector<std::string> steered, unsteered;
  for (const model::Leg& leg : legs) {
    (leg.steering_joint.empty() ? unsteered : steered).push_back(leg.chain->name);
  }
  VehicleConfig config;
  config.model_version = model.version();
  if (!steered.empty() && !unsteered.empty()) {
    throw VehicleError(where + ": " + std::to_string(steered.size()) + " steered legs (chains " +
                       join(steered) + ") and " + std::to_string(unsteered.size()) +
                       " wheels without steering (chains " + join(unsteered) +
                       "): mixed drives are not supported");
  }
  if (!steered.empty()) {
    if (steered.size() < 3) {
      throw VehicleError(
          where + ": " + std::to_string(steered.size()) + " steered leg" +
          (steered.size() == 1 ? "" : "s") + " (chain" + (steered.size() == 1 ? " " : "s ") +
          join(steered) +
          "): omni-steering needs at least 3, a differential drive 2 unsteered wheels");
    }
    config.drive = DriveType::kOmniSteering;
    config.limits.linear = params.max_linear_speed;
    config.limits.steering_rate = std::numeric_limits<double>::infinity();
    double reach = 0.0;
    for (const model::Leg& leg : legs) {
      // The leg's geometry: a vertical steering axis directly above the wheel's horizontal one.
      mobile_base::Leg measured;
      try {
        measured = mobile_base::measure_leg(kin, leg.steering_joint, leg.wheel_joint, leg.wheel_radius);
      } catch (const std::invalid_argument& e) {
        throw VehicleError(where + ": leg chain " + leg.chain->name + ": " + e.what());
      }
      config.steering_legs.push_back(measured);
      WheelConfig w{leg.chain->name,
                    leg.steering_joint,
                    leg.wheel_joint,
                    measured.position,
                    leg.wheel_radius,
                    velocity_limit(model, leg.wheel_joint),
                    velocity_limit(model, leg.steering_joint),
                    1.0};
      config.limits.linear = std::min(config.limits.linear, w.max_wheel_speed * w.radius);
      config.limits.steering_rate = std::min(config.limits.steering_rate, w.max_steering_rate);
      reach = std::max(reach, w.position.norm());
      config.wheels.push_back(std::move(w));
    }
    config.limits.lateral = config.limits.linear;
    config.limits.angular =
        std::min(params.max_angular_speed,
                 reach > 0.0 ? config.limits.linear / reach : params.max_angular_speed);
  } else {
    if (unsteered.size() != 2) {
      throw VehicleError(where + ": " + std::to_string(unsteered.size()) +
                         " wheels without steering (chains " + join(unsteered) +
                         "): a differential drive needs exactly 2 coaxial wheels");
    }
    config.drive = DriveType::kDifferential;
    Eigen::Vector3d centre[2], axis[2];
    for (int i = 0; i < 2; ++i) {
      const model::Leg& leg = legs[static_cast<std::size_t>(i)];
      const int j = kin.joint_index_or_throw(leg.wheel_joint);
      axis[i] = axis_in_base(kin, data, q, j);
      centre[i] = kin.relative_pose(data, q, kin.root_link(), leg.wheel_frame).translation();
      if (std::abs(axis[i].z()) > params.axis_tolerance) {
        throw VehicleError(where + ": wheel joint '" + leg.wheel_joint + "' (chain " +
                           leg.chain->name + ") does not turn about a horizontal axis");
      }
      if (std::abs(axis[i].x()) > params.axis_tolerance) {
        throw VehicleError(where + ": wheel joint '" + leg.wheel_joint + "' (chain " +
                           leg.chain->name + ") does not roll along the base's x axis");
      }
    }
    const Eigen::Vector3d between = centre[1] - centre[0];
    if (axis[0].cross(axis[1]).norm() > params.axis_tolerance || between.norm() < 1e-6 ||
        between.normalized().cross(axis[0]).norm() > params.axis_tolerance) {
      throw VehicleError(where + ": wheels of chains " + join(unsteered) +
                         " are not coaxial: a differential drive needs one common wheel axis");
    }
    config.track = between.head<2>().norm();
    config.limits.linear = params.max_linear_speed;
    for (int i = 0; i < 2; ++i) {
      const model::Leg& leg = legs[static_cast<std::size_t>(i)];
      // A wheel turning by +w about `axis` rolls its centre along axis x z.
      const double forward = axis[i].cross(Eigen::Vector3d::UnitZ()).x();
      WheelConfig w{leg.chain->name,
                    "",
                    leg.wheel_joint,
                    centre[i].head<2>(),
                    leg.wheel_radius,
                    velocity_limit(model, leg.wheel_joint),
                    0.0,
                    forward >= 0.0 ? 1.0 : -1.0};
      config.limits.linear = std::min(config.limits.linear, w.max_wheel_speed * w.radius);
      config.wheels.push_back(std::move(w));
    }
    config.limits.lateral = 0.0;
    config.limits.angular =
        std::min(params.max_angular_speed, 2.0 * config.limits.linear / config.track);
  }
  config.footprint = make_footprint(model, q, posture, config.steering_legs, params);
  config.perception = make_perception(model, q, params);
  return config;
}

}  // namespace concert::nav
