#include "test_support.hpp"

#include <array>
#include <filesystem>
#include <stdexcept>

#include "concert/common/error_text.hpp"
#include "model_fixture.hpp"
#include "modelgen/model_generator.hpp"

namespace concert::modelgen::test {

using module_db::ModuleDescription;

const module_db::ModuleDatabase& public_db() { return testing::module_database(testing::public_module_db()); }

const module_db::ModuleDatabase& own_db() { return testing::module_database(testing::project_module_db()); }

std::string error_of(const std::function<void()>& f) { return error_text<ModelError>(f); }

topology::ModuleTree make_tree(const std::vector<Row>& rows, const module_db::ModuleDatabase* db) {
  topology::ModuleTree tree;
  for (size_t i = 0; i < rows.size(); ++i) {
    topology::ModuleNode n;
    n.index = static_cast<int32_t>(i);
    n.key = std::get<0>(rows[i]);
    n.parent_module = std::get<1>(rows[i]);
    n.parent_connector = std::get<2>(rows[i]);
    if (db != nullptr) {
      if (const ModuleDescription* d = db->find(n.key); d != nullptr && d->esc) n.identity = *d->esc;
    }
    tree.modules.push_back(n);
  }
  return tree;
}

namespace {

Eigen::Isometry3d to_eigen(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  return t;
}

Eigen::Isometry3d motion(const module_db::JointDescription& j, double q) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  if (j.type == module_db::JointType::kPrismatic) {
    m.translation() = j.axis * q;
  } else if (j.type != module_db::JointType::kFixed) {
    m.linear() = Eigen::AngleAxisd(q, j.axis).toRotationMatrix();
  }
  return m;
}

/// root_body_T_body inside one module (eq. 2 with the module's own joints).
Eigen::Isometry3d within(const ModuleDescription& d, int body, const std::map<int, double>& q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  int b = body;
  while (b != d.root_body()) {
    bool found = false;
    for (size_t k = 0; k < d.joints.size(); ++k) {
      const module_db::JointDescription& j = d.joints[k];
      if (j.child_body != b) continue;
      const auto it = q.find(static_cast<int>(k));
      t = j.pose_parent * motion(j, it == q.end() ? 0.0 : it->second) * j.pose_child * t;
      b = j.parent_body;
      found = true;
      break;
    }
    if (!found) throw std::runtime_error("body not connected to the root body");
  }
  return t;
}

}  // namespace

Eigen::Isometry3d urdf_fk(const urdf::ModelInterface& model, const std::string& link, const std::map<std::string, double>& q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  urdf::LinkConstSharedPtr l = model.getLink(link);
  if (!l) throw std::runtime_error("no link " + link);
  while (l->parent_joint) {
    const urdf::Joint& j = *l->parent_joint;
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    const auto it = q.find(j.name);
    const double v = it == q.end() ? 0.0 : it->second;
    const Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
    if (j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS) {
      m.linear() = Eigen::AngleAxisd(v, axis).toRotationMatrix();
    } else if (j.type == urdf::Joint::PRISMATIC) {
      m.translation() = axis * v;
    }
    t = to_eigen(j.parent_to_joint_origin_transform) * m * t;
    l = model.getLink(j.parent_link_name);
  }
  return t;
}

Eigen::Isometry3d description_fk(const module_db::ModuleDatabase& db, const topology::ModuleTree& tree, int module, int tcp_index,
                                 const std::map<int, std::map<int, double>>& q) {
  auto q_of = [&](int m) {
    const auto it = q.find(m);
    return it == q.end() ? std::map<int, double>{} : it->second;
  };
  // Path root -> module.
  std::vector<int> path;
  for (int m = module; m >= 0; m = tree.modules[static_cast<size_t>(m)].parent_module) path.insert(path.begin(), m);
  Eigen::Isometry3d root_body = Eigen::Isometry3d::Identity();  // world = root module's root body
  for (size_t i = 1; i < path.size(); ++i) {
    const ModuleDescription& parent = db.at(tree.modules[static_cast<size_t>(path[i - 1])].key);
    const ModuleDescription& child = db.at(tree.modules[static_cast<size_t>(path[i])].key);
    const int n = tree.modules[static_cast<size_t>(path[i])].parent_connector;
    const module_db::Connector& out = parent.connectors[static_cast<size_t>(parent.output_connectors()[static_cast<size_t>(n - 1)])];
    // Eq. (1): T_{in(parent), in(child)} = T_{in,out}^{parent}; frames of mating connectors coincide.
    const Eigen::Isometry3d in_child = root_body * within(parent, out.body, q_of(path[i - 1])) * out.pose;
    root_body = in_child * child.connectors[static_cast<size_t>(child.input_connector())].pose.inverse();
  }
  const ModuleDescription& d = db.at(tree.modules[static_cast<size_t>(module)].key);
  const module_db::Connector& tcp = d.connectors[static_cast<size_t>(d.tcp_connectors()[static_cast<size_t>(tcp_index)])];
  return root_body * within(d, tcp.body, q_of(module)) * tcp.pose;
}

namespace {

/// A mobile base (`keys`: base, steering FL/RR, steering FR/RL, wheel) with its four legs on
/// connectors 1-4, then `arm` in a chain on connector 5.
std::vector<Row> base_with_arm(const std::array<const char*, 4>& keys, const std::vector<std::string>& arm) {
  const auto& [base, steering_fl_rr, steering_fr_rl, wheel] = keys;
  std::vector<Row> r{{base, -1, -1}};
  int leg_connector = 0;
  for (const char* steering : {steering_fl_rr, steering_fr_rl, steering_fr_rl, steering_fl_rr}) {
    r.emplace_back(steering, 0, ++leg_connector);
    r.emplace_back(wheel, static_cast<int>(r.size()) - 1, 1);
  }
  int parent = 0;
  int connector = 5;
  for (const std::string& key : arm) {
    r.emplace_back(key, parent, connector);
    parent = static_cast<int>(r.size()) - 1;
    connector = 1;
  }
  return r;
}

}  // namespace

std::vector<Row> public_eighteen_module_robot() {
  return base_with_arm({"mobile_platform_concert", "module_steering_concert_fl_rr", "module_steering_concert_fr_rl",
                        "module_wheel_concert"},
                       {"module_joint_yaw_A_concert", "module_joint_elbow_A_concert", "module_link_straight_400_concert",
                        "module_joint_elbow_A_concert", "module_joint_yaw_B_concert", "module_link_straight_400_concert",
                        "module_joint_elbow_B_concert", "module_joint_yaw_B_concert", "passive_end_effector_panel"});
}

std::vector<Row> mobile_robot(const std::vector<std::string>& arm) {
  return base_with_arm({"concert_mobile_base_hub", "concert_steering_fl_rr", "concert_steering_fr_rl", "concert_wheel"},
                       arm);
}

const std::vector<std::string> kMorphologyA{"concert_straight_a", "concert_elbow_a",  "concert_straight_a",
                                            "concert_elbow_a",    "concert_straight_b", "concert_link_400",
                                            "concert_elbow_b",    "concert_drill"};
const std::vector<std::string> kMorphologyB{"concert_straight_a", "concert_elbow_a",    "concert_straight_a",
                                            "concert_link_400",   "concert_elbow_a",    "concert_straight_b",
                                            "concert_link_400",   "concert_elbow_b",    "concert_drill"};

std::vector<Row> two_arm_torso() {
  std::vector<Row> rows = mobile_robot({"concert_base_link_600", "concert_torso_hub"});
  const int torso = static_cast<int>(rows.size()) - 1;
  const auto chain = [&rows](int parent, int connector, const std::vector<std::string>& keys) {
    for (const std::string& key : keys) {
      rows.emplace_back(key, parent, connector);
      parent = static_cast<int>(rows.size()) - 1;
      connector = 1;
    }
  };
  chain(torso, 1, {"concert_elbow_a", "concert_link_elbow_90", "concert_straight_b", "concert_active_gripper_panel"});
  chain(torso, 2, {"concert_elbow_b", "concert_link_elbow_45", "concert_sanding_tool"});
  return rows;
}

simbus::Assembly to_assembly(const std::vector<Row>& rows) {
  // Appended rather than "m" + ...: GCC 12 at -O3 flags that with a -Wrestrict false positive.
  const auto name = [](std::size_t i) {
    std::string n = "m";
    n += std::to_string(i);
    return n;
  };
  simbus::Assembly a;
  a.source = "<test rows>";
  for (const auto& [key, parent, connector] : rows) {
    simbus::MountedModule m;
    m.name = name(a.modules.size());
    m.key = key;
    if (parent >= 0) {
      m.parent = name(static_cast<std::size_t>(parent));
      m.connector = connector;
    }
    a.modules.push_back(std::move(m));
  }
  return a;
}

}  // namespace concert::modelgen::test
