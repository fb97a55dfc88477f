#include "concert/model/robot_model.hpp"

#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

namespace concert::model {
namespace {

Eigen::Isometry3d to_eigen(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  return t;
}

// What the model uses of the SRDF besides the description's lists: <disable_collisions> pairs
// and the `home` group state. A small tinyxml2 read instead of a full SRDF model.
struct SrdfContent {
  std::vector<std::pair<std::string, std::string>> disabled;
  std::map<std::string, double> home;
};

SrdfContent read_srdf(const std::string& srdf, const std::string& where) {
  SrdfContent out;
  if (srdf.empty()) return out;
  tinyxml2::XMLDocument doc;
  if (doc.Parse(srdf.c_str()) != tinyxml2::XML_SUCCESS) {
    throw ModelError(where + ": SRDF: XML parse error: " + doc.ErrorStr());
  }
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) throw ModelError(where + ": SRDF: no <robot> element");
  for (const tinyxml2::XMLElement* e = robot->FirstChildElement("disable_collisions"); e != nullptr;
       e = e->NextSiblingElement("disable_collisions")) {
    const char* a = e->Attribute("link1");
    const char* b = e->Attribute("link2");
    if (a == nullptr || b == nullptr)
      throw ModelError(where + ": SRDF: <disable_collisions> without link1/link2");
    out.disabled.emplace_back(a, b);
  }
  for (const tinyxml2::XMLElement* gs = robot->FirstChildElement("group_state"); gs != nullptr;
       gs = gs->NextSiblingElement("group_state")) {
    const char* name = gs->Attribute("name");
    if (name == nullptr || std::string_view(name) != "home") continue;
    for (const tinyxml2::XMLElement* j = gs->FirstChildElement("joint"); j != nullptr;
         j = j->NextSiblingElement("joint")) {
      const char* joint = j->Attribute("name");
      double value = 0.0;
      if (joint == nullptr || j->QueryDoubleAttribute("value", &value) != tinyxml2::XML_SUCCESS ||
          !std::isfinite(value)) {
        throw ModelError(where + ": SRDF home: joint '" + (joint != nullptr ? joint : "?") +
                         "' has no numeric value");
      }
      out.home[joint] = value;
    }
    break;
  }
  return out;
}

CollisionShape to_shape(const urdf::Collision& c) {
  CollisionShape s;
  s.origin = to_eigen(c.origin);
  switch (c.geometry->type) {
    case urdf::Geometry::BOX: {
      const auto& b = static_cast<const urdf::Box&>(*c.geometry);
      s.type = CollisionShape::Type::kBox;
      s.size = Eigen::Vector3d(b.dim.x, b.dim.y, b.dim.z);
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& cy = static_cast<const urdf::Cylinder&>(*c.geometry);
      s.type = CollisionShape::Type::kCylinder;
      s.size = Eigen::Vector3d(cy.radius, cy.radius, cy.length);
      break;
    }
    case urdf::Geometry::SPHERE: {
      const auto& sp = static_cast<const urdf::Sphere&>(*c.geometry);
      s.type = CollisionShape::Type::kSphere;
      s.size = Eigen::Vector3d::Constant(sp.radius);
      break;
    }
    case urdf::Geometry::MESH: {
      const auto& m = static_cast<const urdf::Mesh&>(*c.geometry);
      s.type = CollisionShape::Type::kMesh;
      s.mesh = m.filename;
      s.size = Eigen::Vector3d(m.scale.x, m.scale.y, m.scale.z);
      break;
    }
  }
  return s;
}

template <typename T, typename Describe>
std::string list_of(const std::vector<T>& items, Describe describe) {
  std::string out;
  for (const T& item : items) out += (out.empty() ? "" : ", ") + describe(item);
  return out.empty() ? "none" : out;
}

std::string describe_ee(const EndEffectorInfo& e) {
  return e.name + " (" + std::string(to_string(e.kind)) + ", chain " + e.chain + ")";
}

std::string describe_chain(const ChainInfo& c) {
  return c.name + " (" + std::string(to_string(c.role)) + ")";
}

/// Pointers to the items `keep` accepts, in the description's order.
template <typename T, typename Keep>
std::vector<const T*> select(const std::vector<T>& items, Keep keep) {
  std::vector<const T*> out;
  for (const T& item : items) {
    if (keep(item)) out.push_back(&item);
  }
  return out;
}

/// The item called `name`; nullptr if there is none.
template <typename T>
const T* find_named(const std::vector<T>& items, std::string_view name) {
  for (const T& item : items) {
    if (item.name == name) return &item;
  }
  return nullptr;
}

}  // namespace

RobotModel::RobotModel(ModelDescription description, kinematics::Model fixed,
                       kinematics::Model planar)
    : description_(std::move(description)), fixed_(std::move(fixed)), planar_(std::move(planar)) {}

std::string RobotModel::where() const {
  return "model version " + std::to_string(description_.version);
}

std::shared_ptr<const RobotModel> RobotModel::build(ModelDescription d) {
  const std::string where = "model version " + std::to_string(d.version);
  auto kin = [&](bool planar) {
    try {
      return kinematics::Model::from_urdf_string(d.urdf, {.planar_base = planar});
    } catch (const kinematics::ModelError& e) {
      throw ModelError(where + ": URDF: " + e.what());
    }
  };
  kinematics::Model fixed = kin(false);
  kinematics::Model planar = kin(true);
  std::shared_ptr<RobotModel> m(new RobotModel(std::move(d), std::move(fixed), std::move(planar)));
  const ModelDescription& desc = m->description_;
  m->limits_ = LimitsTable(desc.joints, where);

  // Every joint, chain end and frame the description names exists in the URDF.
  std::map<std::string, std::string> chain_of_joint;
  for (const JointLimits& j : desc.joints) {
    if (!m->fixed_.joint_index(j.name))
      throw ModelError(where + ": joint '" + j.name + "' is not a moving joint of the URDF");
    chain_of_joint[j.name] = j.chain;
  }
  auto need_frame = [&](const std::string& frame, const std::string& what) {
    if (!m->fixed_.has_frame(frame))
      throw ModelError(where + ": " + what + ": no link '" + frame + "' in the URDF");
  };
  for (const ChainInfo& c : desc.chains) {
    const std::string what = "chain " + c.name;
    need_frame(c.base_link, what + " base_link");
    need_frame(c.tip_link, what + " tip_link");
    for (const std::string& j : c.joints) {
      if (!m->limits_.find(j))
        throw ModelError(where + ": " + what + ": joint '" + j +
                         "' has no row in the limits table");
    }
  }
  for (const EndEffectorInfo& e : desc.end_effectors) need_frame(e.frame, "end-effector " + e.name);
  for (const SensorFrame& s : desc.sensor_frames) {
    need_frame(s.frame, "sensor " + s.name);
    if (!s.end_effector.empty()) (void)m->end_effector(s.end_effector);
  }

  // Link tree with collision geometry (urdfdom: KDL keeps no geometry).
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(desc.urdf);
  if (!urdf) throw ModelError(where + ": URDF cannot be parsed");
  std::function<void(const urdf::LinkConstSharedPtr&, int, const std::string&)> walk =
      [&](const urdf::LinkConstSharedPtr& link, int parent, const std::string& chain) {
        Link node;
        node.name = link->name;
        node.parent = parent;
        node.chain = chain;
        if (parent >= 0) {
          const urdf::JointConstSharedPtr& j = link->parent_joint;
          node.joint = j->name;
          node.origin = to_eigen(j->parent_to_joint_origin_transform);
          node.axis = Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z);
          node.moving = j->type != urdf::Joint::FIXED;
          node.prismatic = j->type == urdf::Joint::PRISMATIC;
          if (node.moving) {
            const auto it = chain_of_joint.find(j->name);
            if (it == chain_of_joint.end()) {
              throw ModelError(where + ": URDF joint '" + j->name +
                               "' moves but has no row in the limits table");
            }
            node.chain = it->second;
          }
        }
        if (link->inertial) {
          node.mass = link->inertial->mass;
          node.com = to_eigen(link->inertial->origin).translation();
        }
        for (const urdf::CollisionSharedPtr& c : link->collision_array) {
          if (c && c->geometry) node.shapes.push_back(to_shape(*c));
        }
        const int self = static_cast<int>(m->links_.size());
        const std::string below = node.chain;
        m->links_.push_back(std::move(node));
        for (const urdf::LinkSharedPtr& child : link->child_links) walk(child, self, below);
      };
  walk(urdf->getRoot(), -1, "");

  SrdfContent srdf = read_srdf(desc.srdf, where);
  m->home_ = std::move(srdf.home);
  for (const auto& [a, b] : srdf.disabled) {
    const int ia = m->link_index(a);
    const int ib = m->link_index(b);
    if (ia < 0 || ib < 0)
      throw ModelError(where + ": SRDF disables collisions of unknown link '" + (ia < 0 ? a : b) +
                       "'");
    m->disabled_.emplace_back(std::min(ia, ib), std::max(ia, ib));
  }
  return m;
}

std::optional<double> RobotModel::home(std::string_view joint) const {
  const auto it = home_.find(std::string(joint));
  if (it == home_.end()) return std::nullopt;
  return it->second;
}

Eigen::VectorXd RobotModel::home_posture() const {
  const kinematics::Model& kin = kinematics();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(kin.dof());
  for (int i = 0; i < kin.dof(); ++i) {
    if (kin.is_virtual_joint(i)) continue;
    const std::string& joint = kin.joint_names()[static_cast<std::size_t>(i)];
    double value = home(joint).value_or(0.0);
    if (const JointLimits* row = limits_.find(joint)) {
      const double lower = std::isfinite(row->lower) ? row->lower : -M_PI;
      const double upper = std::isfinite(row->upper) ? row->upper : M_PI;
      value = std::clamp(value, lower, upper);
    }
    q[i] = value;
  }
  return q;
}

int RobotModel::link_index(std::string_view name) const {
  for (std::size_t i = 0; i < links_.size(); ++i) {
    if (links_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::vector<const ChainInfo*> RobotModel::chains(ChainRole role) const {
  return select(description_.chains, [role](const ChainInfo& c) { return c.role == role; });
}

const ChainInfo& RobotModel::chain(std::string_view name) const {
  if (const ChainInfo* c = find_named(description_.chains, name)) return *c;
  throw ModelError(where() + ": no chain '" + std::string(name) +
                   "' (chains: " + list_of(description_.chains, describe_chain) + ")");
}

const ChainInfo& RobotModel::arm() const {
  const std::vector<const ChainInfo*> arms = chains(ChainRole::kArm);
  if (arms.size() == 1) return *arms.front();
  const std::string all = list_of(description_.chains, describe_chain);
  throw ModelError(where() +
                   (arms.empty()
                        ? ": no arm"
                        : ": " + std::to_string(arms.size()) + " arms, select one by name") +
                   " (chains: " + all + ")");
}

std::vector<Leg> RobotModel::legs() const {
  std::vector<Leg> out;
  for (const ChainInfo* c : chains(ChainRole::kLeg)) {
    Leg leg;
    leg.chain = c;
    const EndEffectorInfo* wheel = nullptr;
    for (const EndEffectorInfo& e : description_.end_effectors) {
      if (e.chain == c->name && e.kind == EndEffectorKind::kWheel) wheel = &e;
    }
    if (wheel == nullptr || c->joints.empty()) {
      throw ModelError(where() + ": leg chain " + c->name +
                       " has no wheel end-effector or no moving joint");
    }
    leg.wheel_frame = wheel->frame;
    leg.wheel_joint = c->joints.back();
    if (c->joints.size() >= 2) leg.steering_joint = c->joints[c->joints.size() - 2];
    // Wheel radius: the largest collision cylinder of the wheel joint's link that turns about
    // its own axis.
    const int wheel_index = fixed_.joint_index_or_throw(leg.wheel_joint);
    const int link = link_index(fixed_.joint_child_link(wheel_index));
    const Eigen::Vector3d axis = links_[static_cast<std::size_t>(link)].axis.normalized();
    for (const CollisionShape& s : links_[static_cast<std::size_t>(link)].shapes) {
      if (s.type != CollisionShape::Type::kCylinder) continue;
      if (std::abs(std::abs((s.origin.linear().col(2)).dot(axis)) - 1.0) > 1e-6) continue;
      leg.wheel_radius = std::max(leg.wheel_radius, s.size.x());
    }
    if (leg.wheel_radius <= 0.0) {
      throw ModelError(where() + ": leg chain " + c->name + ": wheel link '" +
                       links_[static_cast<std::size_t>(link)].name +
                       "' has no collision cylinder about the wheel axis (no wheel radius)");
    }
    out.push_back(std::move(leg));
  }
  return out;
}

std::vector<const EndEffectorInfo*> RobotModel::end_effectors(EndEffectorKind kind) const {
  return select(description_.end_effectors,
                [kind](const EndEffectorInfo& e) { return e.kind == kind; });
}

const EndEffectorInfo& RobotModel::end_effector(std::string_view name) const {
  if (const EndEffectorInfo* e = find_named(description_.end_effectors, name)) return *e;
  throw ModelError(where() + ": no end-effector '" + std::string(name) +
                   "' (end-effectors: " + list_of(description_.end_effectors, describe_ee) + ")");
}

const EndEffectorInfo& RobotModel::tool() const {
  std::vector<const EndEffectorInfo*> tools;
  for (const EndEffectorInfo& e : description_.end_effectors) {
    if (e.kind == EndEffectorKind::kWheel) continue;
    for (const ChainInfo& c : description_.chains) {
      if (c.name == e.chain && (c.role == ChainRole::kArm || c.role == ChainRole::kTool))
        tools.push_back(&e);
    }
  }
  if (tools.size() == 1) return *tools.front();
  throw ModelError(
      where() +
      (tools.empty() ? ": no tool on an arm" : ": several arm tools, select one by kind or name") +
      " (end-effectors: " + list_of(description_.end_effectors, describe_ee) + ")");
}

const EndEffectorInfo& RobotModel::tool(EndEffectorKind kind) const {
  std::vector<const EndEffectorInfo*> found;
  for (const EndEffectorInfo* e : end_effectors(kind)) {
    for (const ChainInfo& c : description_.chains) {
      if (c.name == e->chain && c.role != ChainRole::kLeg) found.push_back(e);
    }
  }
  if (found.size() == 1) return *found.front();
  throw ModelError(
      where() + ": " + (found.empty() ? "no" : "several") + " " + std::string(to_string(kind)) +
      " tool on an arm (end-effectors: " + list_of(description_.end_effectors, describe_ee) + ")");
}

std::vector<const SensorFrame*> RobotModel::sensor_frames(SensorKind kind) const {
  return select(description_.sensor_frames,
                [kind](const SensorFrame& s) { return s.kind == kind; });
}

const SensorFrame* RobotModel::sensor_of(const EndEffectorInfo& ee, SensorKind kind) const {
  for (const SensorFrame& s : description_.sensor_frames) {
    if (s.kind == kind && s.end_effector == ee.name) return &s;
  }
  return nullptr;
}

const SensorFrame& RobotModel::sensor(const EndEffectorInfo& ee, SensorKind kind) const {
  if (const SensorFrame* s = sensor_of(ee, kind)) return *s;
  std::vector<SensorFrame> carried;
  for (const SensorFrame& s : description_.sensor_frames) {
    if (s.end_effector == ee.name) carried.push_back(s);
  }
  throw ModelError(where() + ": end-effector '" + ee.name + "' has no " +
                   std::string(to_string(kind)) + " sensor (it carries: " +
                   list_of(carried,
                           [](const SensorFrame& s) {
                             return s.name + " (" + std::string(to_string(s.kind)) + ")";
                           }) +
                   ")");
}

}  // namespace concert::model
