#include "planner/planning_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "concert/collision/link_shapes.hpp"

namespace concert::planner {

const char* to_string(Constraint constraint) {
  switch (constraint) {
    case Constraint::kNone: return "none";
    case Constraint::kJointLimit: return "joint limit";
    case Constraint::kSelfCollision: return "self collision";
    case Constraint::kEnvironmentCollision: return "environment collision";
    case Constraint::kFloor: return "floor";
    case Constraint::kTorqueLimit: return "torque limit";
  }
  return "?";
}

const char* to_string(Status status) {
  switch (status) {
    case Status::kSucceeded: return "succeeded";
    case Status::kNoModel: return "no model";
    case Status::kStaleModel: return "stale model";
    case Status::kInvalidRequest: return "invalid request";
    case Status::kInvalidStart: return "invalid start";
    case Status::kUnreachable: return "unreachable";
    case Status::kNoPath: return "no path";
  }
  return "?";
}

// An axis within this (cosine) of a plane's normal crosses it; within this of 0, lies in it.
constexpr double kAxisTolerance = 1e-3;

namespace {

// The furthest a shape (pose `at` in some frame) reaches along that frame's z.
double top_along_z(const LinkShape& shape, const Eigen::Isometry3d& at) {
  Eigen::Vector3d half = 0.5 * shape.size;
  if (shape.type == LinkShape::Type::kCylinder) half = {shape.size.x(), shape.size.x(), 0.5 * shape.size.z()};
  if (shape.type == LinkShape::Type::kSphere) half = Eigen::Vector3d::Constant(shape.size.x());
  double top = -std::numeric_limits<double>::infinity();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d v((corner & 1) ? half.x() : -half.x(), (corner & 2) ? half.y() : -half.y(),
                            (corner & 4) ? half.z() : -half.z());
    top = std::max(top, (at * shape.origin * v).z());
  }
  return top;
}

}  // namespace

// The module database describes a drill module's body and not its bit: its shapes end behind the
// TCP (0.105 m on the CONCERT drill), so without a shape of its own the bit passes through walls
// unseen, and planned paths swept it into them (holes cut at no mark, safety stops on the arm's
// RMS torque as it dragged). The bit is a cylinder along the TCP's z, from the TCP back to where
// the shapes rigidly attached to it end (the bounding box of each, a little conservative).
void PlanningModel::add_drill_bits(double radius) {
  std::vector<LinkNode>& links = links_;
  for (const EndEffectorInfo* ee : robot_->end_effectors(model::EndEffectorKind::kDrill)) {
    const int tcp = robot_->link_index(ee->frame);
    if (tcp < 0) continue;
    // Up from the TCP through fixed joints to the moving link carrying it, each link's pose in
    // the TCP's frame.
    double top = -std::numeric_limits<double>::infinity();
    Eigen::Isometry3d tcp_T_link = Eigen::Isometry3d::Identity();
    for (int l = tcp; l >= 0;) {
      const LinkNode& node = links[static_cast<std::size_t>(l)];
      for (const LinkShape& shape : node.shapes) top = std::max(top, top_along_z(shape, tcp_T_link));
      if (node.full_index >= 0 || node.parent < 0) break;
      tcp_T_link = tcp_T_link * node.origin.inverse();
      l = node.parent;
    }
    const double length = -top;
    if (!std::isfinite(length) || length <= 0.0) continue;  // the body reaches the TCP: nothing sticks out
    LinkShape bit;
    bit.type = LinkShape::Type::kCylinder;
    bit.size = {radius, radius, length};
    bit.origin = Eigen::Translation3d(0.0, 0.0, -0.5 * length) * Eigen::Isometry3d::Identity();
    links[static_cast<std::size_t>(tcp)].shapes.push_back(bit);
    model::CollisionShape shape;
    shape.type = model::CollisionShape::Type::kCylinder;
    shape.size = bit.size;
    shape.origin = bit.origin;
    added_[tcp].push_back(shape);
  }
}

std::shared_ptr<const PlanningModel> PlanningModel::build(const ModelDescription& description, const Params& params) {
  try {
    return build(model::RobotModel::build(description), params);
  } catch (const model::ModelError& e) {
    throw PlannerError(e.what());
  }
}

std::shared_ptr<const PlanningModel> PlanningModel::build(std::shared_ptr<const model::RobotModel> robot, const Params& params) {
  std::shared_ptr<PlanningModel> m(new PlanningModel(robot->planar_kinematics()));
  m->robot_ = robot;
  const kinematics::Model& k = m->kinematics_;
  const std::string where = robot->where();

  // Planned joints: the virtual base joints, then the joints of every arm chain.
  std::vector<std::string> arm_joints;
  for (const model::ChainInfo* c : robot->chains(model::ChainRole::kArm)) {
    for (const std::string& j : c->joints) arm_joints.push_back(j);
  }
  if (arm_joints.empty()) throw PlannerError(where + ": no chain with role \"arm\" (nothing to plan for)");
  for (int i = 0; i < k.num_virtual_joints(); ++i) m->planned_.push_back(i);
  for (const std::string& j : arm_joints) m->planned_.push_back(k.joint_index_or_throw(j));
  const int n = static_cast<int>(m->planned_.size());
  m->lower_.resize(n);
  m->upper_.resize(n);
  m->velocity_.resize(n);
  m->torque_ = Eigen::VectorXd::Zero(k.dof());
  for (int i = 0; i < n; ++i) {
    const int fi = m->planned_[static_cast<std::size_t>(i)];
    m->planned_names_.push_back(k.joint_names()[static_cast<std::size_t>(fi)]);
    if (k.is_virtual_joint(fi)) {
      m->lower_[i] = -std::numeric_limits<double>::infinity();
      m->upper_[i] = std::numeric_limits<double>::infinity();
      m->velocity_[i] = i == 2 ? params.base_angular_velocity : params.base_linear_velocity;
      continue;
    }
    // The limits table with the limits rule: positions within [lower, upper] (a continuous
    // joint within one turn), velocities within the limit, static torques within the
    // continuous torque.
    const model::JointLimits& lim = robot->limits().at(m->planned_names_.back());
    m->lower_[i] = std::isfinite(lim.lower) ? lim.lower : -M_PI;
    m->upper_[i] = std::isfinite(lim.upper) ? lim.upper : M_PI;
    m->velocity_[i] = lim.velocity;
    m->torque_[fi] = model::planning_torque_limit(lim);
  }

  // Links with their collision primitives (meshes are reported, not used).
  std::set<std::string> leg_chains;
  for (const model::ChainInfo* c : robot->chains(model::ChainRole::kLeg)) leg_chains.insert(c->name);
  // Rigid group: the nearest planned arm joint at or above the link (-1: the base group).
  const std::vector<int> groups = collision::rigid_groups(*robot, arm_joints);
  for (const model::Link& link : robot->links()) {
    LinkNode node;
    node.name = link.name;
    node.parent = link.parent;
    node.origin = link.origin;
    node.axis = link.axis;
    node.prismatic = link.prismatic;
    node.leg = leg_chains.count(link.chain) > 0;
    node.mass = link.mass;
    node.com = link.com;
    node.rigid_group = groups[m->links_.size()];
    if (link.moving) node.full_index = k.joint_index_or_throw(link.joint);
    for (const model::CollisionShape& c : link.shapes) {
      LinkShape s;
      s.origin = c.origin;
      s.size = c.size;
      switch (c.type) {
        case model::CollisionShape::Type::kBox: s.type = LinkShape::Type::kBox; break;
        case model::CollisionShape::Type::kCylinder: s.type = LinkShape::Type::kCylinder; break;
        case model::CollisionShape::Type::kSphere: s.type = LinkShape::Type::kSphere; break;
        case model::CollisionShape::Type::kMesh:
          m->ignored_.push_back(link.name + ": mesh collision geometry (planner uses primitives only)");
          continue;
      }
      node.shapes.push_back(s);
    }
    m->links_.push_back(std::move(node));
  }

  if (params.drill_bit_radius > 0.0) m->add_drill_bits(params.drill_bit_radius);

  const std::size_t nl = m->links_.size();
  m->disabled_.assign(nl, std::vector<bool>(nl, false));
  for (std::size_t a = 0; a < nl; ++a) {
    for (std::size_t b = 0; b < nl; ++b) {
      if (a == b || m->links_[a].rigid_group == m->links_[b].rigid_group) m->disabled_[a][b] = true;
    }
  }
  for (const auto& [a, b] : robot->disabled_pairs()) {
    m->disabled_[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] = true;
    m->disabled_[static_cast<std::size_t>(b)][static_cast<std::size_t>(a)] = true;
  }

  // Base height: the lowest leg collision point of the zero posture rests on the floor.
  m->base_height_ = params.base_height;
  if (std::isnan(m->base_height_)) {
    m->base_height_ = params.floor_height;
    std::vector<Eigen::Isometry3d> poses;
    const double saved = m->base_height_;
    m->base_height_ = 0.0;
    m->link_poses(Eigen::VectorXd::Zero(k.dof()), poses);
    double lowest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < nl; ++i) {
      if (!m->links_[i].leg) continue;
      for (const LinkShape& s : m->links_[i].shapes) {
        const Eigen::Isometry3d t = poses[i] * s.origin;
        double extent = 0.0;
        if (s.type == LinkShape::Type::kBox) {
          extent = 0.5 * (t.linear().cwiseAbs() * s.size).z();
        } else if (s.type == LinkShape::Type::kSphere) {
          extent = s.size.x();
        } else {
          const Eigen::Vector3d axis = t.linear().col(2);
          extent = 0.5 * s.size.z() * std::abs(axis.z()) + s.size.x() * std::sqrt(std::max(0.0, 1.0 - axis.z() * axis.z()));
        }
        lowest = std::min(lowest, t.translation().z() - extent);
      }
    }
    m->base_height_ = std::isfinite(lowest) ? params.floor_height - lowest : saved;
  }

  // Mirror image of arm postures about the vertical plane through the first arm joint that
  // holds the axis of the first arm joint across it (a horizontal axis: the shoulder).
  // Reflecting a posture in a plane negates each revolute angle whose axis lies in the plane
  // and keeps each one whose axis crosses it (prismatic joints the other way round), so the
  // signs are read off the joint axes at q = 0. The image is exact when the modules' offsets
  // lie in that plane (the CONCERT modules': MirroredArmReflectsTheCamera), approximate
  // otherwise; the planner uses it as a seed and checks every result.
  {
    std::vector<Eigen::Isometry3d> poses;
    m->link_poses(Eigen::VectorXd::Zero(k.dof()), poses);
    std::map<int, Eigen::Vector3d> axis_of;  // full index -> world axis at q = 0
    for (std::size_t i = 0; i < nl; ++i) {
      if (m->links_[i].full_index >= 0) axis_of[m->links_[i].full_index] = poses[i].linear() * m->links_[i].axis;
    }
    std::optional<Eigen::Vector3d> normal;
    for (int i = 3; i < n && !normal; ++i) {
      const Eigen::Vector3d& a = axis_of[m->planned_[static_cast<std::size_t>(i)]];
      if (std::abs(a.z()) < kAxisTolerance) normal = a.normalized();
    }
    Eigen::VectorXd signs(n - 3);
    bool clean = normal.has_value();
    for (int i = 3; i < n && clean; ++i) {
      const int fi = m->planned_[static_cast<std::size_t>(i)];
      const double across = std::abs(axis_of[fi].normalized().dot(*normal));
      bool prismatic = false;
      for (const LinkNode& l : m->links_) prismatic = prismatic || (l.full_index == fi && l.prismatic);
      if (across > 1.0 - kAxisTolerance) {
        signs[i - 3] = prismatic ? -1.0 : 1.0;
      } else if (across < kAxisTolerance) {
        signs[i - 3] = prismatic ? 1.0 : -1.0;
      } else {
        clean = false;  // an oblique axis: no mirror image within the joint space
      }
    }
    if (clean) m->arm_mirror_ = signs;
  }
  return m;
}

std::optional<Eigen::VectorXd> PlanningModel::mirrored_arm(const Eigen::VectorXd& arm) const {
  if (!arm_mirror_ || arm.size() != arm_mirror_->size()) return std::nullopt;
  Eigen::VectorXd out = arm.cwiseProduct(*arm_mirror_);
  const Eigen::Index n = arm.size();
  if ((out.array() < lower_.tail(n).array()).any() || (out.array() > upper_.tail(n).array()).any()) return std::nullopt;
  return out;
}

bool PlanningModel::pair_disabled(int a, int b) const {
  return disabled_[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)];
}

void PlanningModel::link_poses(const Eigen::VectorXd& q, std::vector<Eigen::Isometry3d>& poses) const {
  // One pass over the tree for all links: collision checking needs every link, and KDL's
  // per-frame solver would walk the chain again for each of them.
  poses.resize(links_.size());
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = Eigen::Vector3d(q[0], q[1], base_height_);
  base.linear() = Eigen::AngleAxisd(q[2], Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (std::size_t i = 0; i < links_.size(); ++i) {
    const LinkNode& l = links_[i];
    if (l.parent < 0) {
      poses[i] = base;
      continue;
    }
    Eigen::Isometry3d t = poses[static_cast<std::size_t>(l.parent)] * l.origin;
    if (l.full_index >= 0) {
      const double v = q[l.full_index];
      if (l.prismatic) {
        t.translate(l.axis * v);
      } else {
        t.rotate(Eigen::AngleAxisd(v, l.axis));
      }
    }
    poses[i] = t;
  }
}

void PlanningModel::static_torques(const std::vector<Eigen::Isometry3d>& poses, int contact_link, const Eigen::Vector3d& force,
                                   Eigen::VectorXd& tau) const {
  // Subtree mass and first moment (sum m c) per link, leaves first (links_ is parents first).
  thread_local std::vector<double> mass;
  thread_local std::vector<Eigen::Vector3d> moment;
  const std::size_t nl = links_.size();
  mass.resize(nl);
  moment.resize(nl);
  for (std::size_t i = 0; i < nl; ++i) {
    mass[i] = links_[i].mass;
    moment[i] = links_[i].mass * (poses[i] * links_[i].com);
  }
  for (std::size_t i = nl; i-- > 1;) {
    const auto p = static_cast<std::size_t>(links_[i].parent);
    mass[p] += mass[i];
    moment[p] += moment[i];
  }
  tau.setZero(kinematics_.dof());
  for (std::size_t i = 0; i < nl; ++i) {
    const LinkNode& l = links_[i];
    if (l.full_index < 0) continue;
    const Eigen::Vector3d a = poses[i].linear() * l.axis;
    // Gravity m g acts at the subtree's centre of mass c: moment about the joint (c - p) x m g.
    tau[l.full_index] = l.prismatic ? -a.dot(mass[i] * gravity_)
                                    : -a.dot((moment[i] - mass[i] * poses[i].translation()).cross(gravity_));
  }
  if (contact_link < 0) return;
  const Eigen::Vector3d at = poses[static_cast<std::size_t>(contact_link)].translation();
  for (int i = contact_link; i >= 0; i = links_[static_cast<std::size_t>(i)].parent) {
    const LinkNode& l = links_[static_cast<std::size_t>(i)];
    if (l.full_index < 0) continue;
    const Eigen::Isometry3d& t = poses[static_cast<std::size_t>(i)];
    const Eigen::Vector3d a = t.linear() * l.axis;
    tau[l.full_index] -= l.prismatic ? a.dot(force) : a.dot((at - t.translation()).cross(force));
  }
}

Eigen::Isometry3d PlanningModel::link_pose(const Eigen::VectorXd& q, const std::string& link) const {
  const int i = link_index(link);
  if (i < 0) throw PlannerError(robot_->where() + ": no link '" + link + "'");
  std::vector<Eigen::Isometry3d> poses;
  link_poses(q, poses);
  return poses[static_cast<std::size_t>(i)];
}

int PlanningModel::link_index(const std::string& name) const {
  for (std::size_t i = 0; i < links_.size(); ++i) {
    if (links_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

const EndEffectorInfo& PlanningModel::tool(const std::string& name) const {
  try {
    return name.empty() ? robot_->tool() : robot_->end_effector(name);
  } catch (const model::ModelError& e) {
    throw PlannerError(e.what());
  }
}

std::string PlanningModel::camera_frame(const EndEffectorInfo& tool) const {
  try {
    return robot_->sensor(tool, model::SensorKind::kCamera).frame;
  } catch (const model::ModelError& e) {
    throw PlannerError(e.what());
  }
}

Eigen::VectorXd PlanningModel::to_full(const Eigen::VectorXd& planned, const Eigen::VectorXd& full_template) const {
  Eigen::VectorXd q = full_template;
  for (std::size_t i = 0; i < planned_.size(); ++i) q[planned_[i]] = planned[static_cast<Eigen::Index>(i)];
  return q;
}

Eigen::VectorXd PlanningModel::to_planned(const Eigen::VectorXd& full) const {
  Eigen::VectorXd q(dof());
  for (std::size_t i = 0; i < planned_.size(); ++i) q[static_cast<Eigen::Index>(i)] = full[planned_[i]];
  return q;
}

Eigen::VectorXd PlanningModel::full_from_named(const std::vector<std::string>& names, const std::vector<double>& positions,
                                               const Eigen::Vector3d& base) const {
  if (names.size() != positions.size()) {
    throw PlannerError("joint state: " + std::to_string(names.size()) + " names but " + std::to_string(positions.size()) +
                       " positions");
  }
  Eigen::VectorXd q = Eigen::VectorXd::Zero(full_dof());
  q.head<3>() = base;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto idx = kinematics_.joint_index(names[i]);
    if (!idx) throw PlannerError("joint state: joint '" + names[i] + "' is not in " + robot_->where());
    q[*idx] = positions[i];
  }
  return q;
}

}  // namespace concert::planner
