// chi -> phi (paper section 4.3.3, eq. 1-2) and the model's lists.

#include "concert/model_generation/generator.hpp"
#include "resting_posture.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

namespace concert::model_generation {

using module_db::ConnectorRole;
using module_db::JointType;
using module_db::ModuleDescription;
using module_db::ModuleType;

int PhysicalTree::body_index(const std::string& name) const {
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

double PhysicalTree::mass() const {
  double m = 0.0;
  for (const PhysicalBody& b : bodies) m += b.inertial.mass;
  return m;
}

namespace {

/// Bijective base-26 tag: 0 -> A, 25 -> Z, 26 -> AA.
std::string tag_name(int n) {
  std::string s;
  ++n;
  while (n > 0) {
    const int r = (n - 1) % 26;
    s.insert(s.begin(), static_cast<char>('A' + r));
    n = (n - 1) / 26;
  }
  return s;
}

std::string sfx(const std::string& tag) { return tag.empty() ? "" : "_" + tag; }

std::string module_label(const topology::ModuleNode& node, int index) {
  std::string s = "module " + std::to_string(index);
  if (!node.key.empty()) s += " ('" + node.key + "')";
  if (!node.slave_positions.empty()) s += " at slave " + std::to_string(node.slave_positions.front());
  return s;
}

/// Inertial of a body re-expressed in a link frame: link_T_body = offset.
module_db::Inertial to_link(const module_db::Inertial& in, const Pose& offset) {
  module_db::Inertial out;
  out.mass = in.mass;
  out.com = offset * in.com;
  out.inertia = offset.linear() * in.inertia * offset.linear().transpose();
  return out;
}

/// Adds a point mass `m` at `p` (link frame) to an inertial (parallel-axis theorem).
void add_point_mass(module_db::Inertial& in, double m, const Eigen::Vector3d& p) {
  const double total = in.mass + m;
  if (total <= 0.0) return;
  const Eigen::Vector3d com = (in.mass * in.com + m * p) / total;
  auto shift = [](const Eigen::Vector3d& d) {
    return Eigen::Matrix3d(d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  };
  in.inertia = in.inertia + in.mass * shift(in.com - com) + m * shift(p - com);
  in.com = com;
  in.mass = total;
}

std::string end_effector_word(const ModuleDescription& d) {
  if (d.type == ModuleType::kWheel) return "wheel";
  std::string w = d.tags.empty() ? "ee" : d.tags.front();
  if (w == "end_effector") w = "ee";
  for (char& c : w) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return w;
}

/// Kind of an end-effector module: a wheel module is a wheel, else the first semantic tag that
/// names a kind (the project database tags "drill", "gripper", "sanding_tool"...; the public
/// one carries its header type, e.g. "drill", "spraying_tool").
model::EndEffectorKind end_effector_kind(const ModuleDescription& d) {
  using model::EndEffectorKind;
  if (d.type == ModuleType::kWheel) return EndEffectorKind::kWheel;
  for (const std::string& t : d.tags) {
    if (t == "drill") return EndEffectorKind::kDrill;
    if (t == "gripper" || t == "active_gripper" || t == "passive_gripper") return EndEffectorKind::kGripper;
    if (t == "sanding_tool" || t == "sanding") return EndEffectorKind::kSanding;
    if (t == "spraying_tool" || t == "spraying") return EndEffectorKind::kSpraying;
    if (t == "camera") return EndEffectorKind::kCamera;
  }
  return EndEffectorKind::kOther;
}

/// The sensor a module frame carries, if it is a sensor frame.
std::optional<model::SensorKind> sensor_kind(module_db::FrameKind kind) {
  switch (kind) {
    case module_db::FrameKind::kCamera:
      return model::SensorKind::kCamera;
    case module_db::FrameKind::kLidar:
      return model::SensorKind::kLidar;
    case module_db::FrameKind::kSonar:
      return model::SensorKind::kSonar;
    case module_db::FrameKind::kImu:
      return model::SensorKind::kImu;
    default:
      return std::nullopt;
  }
}

struct ChainRecord {
  ChainInfo info;
  bool has_wheel = false;
  bool has_tool = false;
  bool has_joint = false;
  std::string last_body;
};

struct State {
  std::string tag;
  int j = 0;
  int l = 0;
};

class Builder {
 public:
  Builder(const ModelGenerator& gen, const topology::ModuleTree& tree) : gen_(gen), tree_(tree) {}

  void run() {
    const auto& mods = tree_.modules;
    if (mods.empty()) throw ModelError("module tree is empty");
    children_.assign(mods.size(), {});
    int root = -1;
    for (size_t i = 0; i < mods.size(); ++i) {
      const int p = mods[i].parent_module;
      if (p < 0) {
        if (root >= 0) throw ModelError(module_label(mods[i], static_cast<int>(i)) + ": second root module (module " + std::to_string(root) + " is the first)");
        root = static_cast<int>(i);
      } else {
        if (p >= static_cast<int>(mods.size()) || p == static_cast<int>(i)) {
          throw ModelError(module_label(mods[i], static_cast<int>(i)) + ": parent_module " + std::to_string(p) + " does not exist");
        }
        children_[static_cast<size_t>(p)].push_back(static_cast<int>(i));
      }
    }
    if (root < 0) throw ModelError("module tree has no root module");
    desc_.assign(mods.size(), nullptr);
    for (size_t i = 0; i < mods.size(); ++i) desc_[i] = &gen_.describe(mods[i]);
    visited_.assign(mods.size(), false);
    State s;
    expand(root, -1, Pose::Identity(), s, false);
    for (size_t i = 0; i < mods.size(); ++i) {
      if (!visited_[i]) throw ModelError(module_label(mods[i], static_cast<int>(i)) + ": not reachable from the root (cycle in parent_module)");
    }
  }

  PhysicalTree phi;
  std::vector<ChainRecord> chains;
  std::vector<EndEffectorInfo> ees;
  std::vector<model::SensorFrame> sensors;
  std::vector<const ModuleDescription*> desc_;

 private:
  int add_body(PhysicalBody b) {
    if (!names_.insert(b.name).second) throw ModelError("duplicate link name '" + b.name + "'");
    phi.bodies.push_back(std::move(b));
    return static_cast<int>(phi.bodies.size()) - 1;
  }
  void add_joint(PhysicalJoint j) {
    if (!names_.insert(j.name).second) throw ModelError("duplicate joint name '" + j.name + "'");
    phi.joints.push_back(std::move(j));
  }
  ChainRecord* chain(const std::string& tag) {
    const auto it = chain_index_.find(tag);
    return it == chain_index_.end() ? nullptr : &chains[it->second];
  }

  int make_body(int m, const ModuleDescription& d, int b, const Pose& offset, const std::string& name, const std::string& tag) {
    PhysicalBody pb;
    pb.name = name;
    pb.module = m;
    pb.module_body = b;
    pb.chain = tag;
    const module_db::Body& body = d.bodies[static_cast<size_t>(b)];
    pb.inertial = to_link(body.inertial, offset);
    for (module_db::Shape s : body.visuals) {
      s.pose = offset * s.pose;
      pb.visuals.push_back(std::move(s));
    }
    for (module_db::Shape s : body.collisions) {
      s.pose = offset * s.pose;
      pb.collisions.push_back(std::move(s));
    }
    const int idx = add_body(std::move(pb));
    if (ChainRecord* c = chain(tag)) c->last_body = name;
    return idx;
  }

  int make_frame(int m, int parent, const Pose& origin, const std::string& name, const std::string& tag) {
    PhysicalBody pb;
    pb.name = name;
    pb.module = m;
    pb.chain = tag;
    pb.massless = true;
    const int idx = add_body(std::move(pb));
    PhysicalJoint j;
    j.name = "fixed_" + name;
    j.parent = parent;
    j.child = idx;
    j.origin = origin;
    j.module = m;
    j.chain = tag;
    add_joint(std::move(j));
    return idx;
  }

  void expand(int m, int attach_body, const Pose& attach_pose, State s, bool parent_is_hub) {
    const auto& node = tree_.modules[static_cast<size_t>(m)];
    const ModuleDescription& d = *desc_[static_cast<size_t>(m)];
    visited_[static_cast<size_t>(m)] = true;
    const bool is_root = attach_body < 0;
    if (is_root) {
      if (!d.is_hub()) s = State{tag_name(next_tag_++), 0, 0};
    } else if (parent_is_hub) {
      s = State{tag_name(next_tag_++), 0, 0};
    }
    if (!s.tag.empty() && chain(s.tag) == nullptr) {
      ChainRecord c;
      c.info.name = s.tag;
      c.info.base_link = is_root ? "base_link" : phi.bodies[static_cast<size_t>(attach_body)].name;
      chain_index_[s.tag] = chains.size();
      chains.push_back(std::move(c));
    }
    ChainRecord* ch = chain(s.tag);
    if (ch != nullptr) {
      ch->info.modules.push_back(m);
      if (d.type == ModuleType::kWheel) ch->has_wheel = true;
      if (d.type == ModuleType::kEndEffector) ch->has_tool = true;
      if (d.type == ModuleType::kJoint) ch->has_joint = true;
    }
    const std::string T = sfx(s.tag);

    // Root body of the module.
    const int rb = d.root_body();
    std::string root_name;
    if (is_root) {
      root_name = "base_link";
    } else if (d.type == ModuleType::kJoint || (d.actuated() && d.is_end_effector())) {
      root_name = "L_" + std::to_string(s.j) + "_proximal" + T;
    } else if (d.is_hub()) {
      ++s.l;
      root_name = "L_" + std::to_string(s.j) + "_hub_" + std::to_string(s.l) + T;
    } else if (d.type == ModuleType::kEndEffector) {
      root_name = "L_" + std::to_string(s.j) + "_ee" + T;
    } else {
      ++s.l;
      root_name = "L_" + std::to_string(s.j) + "_link_" + std::to_string(s.l) + T;
    }
    std::vector<int> urdf_of(d.bodies.size(), -1);
    std::vector<Pose> offset_of(d.bodies.size(), Pose::Identity());
    urdf_of[static_cast<size_t>(rb)] = make_body(m, d, rb, Pose::Identity(), root_name, s.tag);
    if (!is_root) {
      const int in = d.input_connector();
      // Eq. (1): the parent's output frame and this module's input frame coincide.
      PhysicalJoint j;
      j.name = "fixed_" + root_name;
      j.parent = attach_body;
      j.child = urdf_of[static_cast<size_t>(rb)];
      j.origin = attach_pose * d.connectors[static_cast<size_t>(in)].pose.inverse();
      j.module = m;
      j.chain = s.tag;
      j.connection = true;
      add_joint(std::move(j));
    }
    // Eq. (2): bodies of the module in joint-tree order (file order among siblings).
    std::vector<int> stack{rb};
    while (!stack.empty()) {
      const int b = stack.front();
      stack.erase(stack.begin());
      for (const module_db::JointDescription& jd : d.joints) {
        if (jd.parent_body != b) continue;
        const size_t c = static_cast<size_t>(jd.child_body);
        PhysicalJoint j;
        j.parent = urdf_of[static_cast<size_t>(b)];
        j.module = m;
        j.chain = s.tag;
        std::string child_name;
        if (jd.actuated()) {
          ++s.j;
          s.l = 0;
          j.name = "J" + std::to_string(s.j) + T;
          j.type = jd.type;
          j.axis = jd.axis;
          j.description = &jd;
          j.origin = offset_of[static_cast<size_t>(b)] * jd.pose_parent;
          offset_of[c] = jd.pose_child;
          child_name = "L_" + std::to_string(s.j) + T;
          if (ch != nullptr) ch->info.joints.push_back(j.name);
        } else {
          ++s.l;
          child_name = "L_" + std::to_string(s.j) + "_link_" + std::to_string(s.l) + T;
          j.name = "fixed_" + child_name;
          j.origin = offset_of[static_cast<size_t>(b)] * jd.pose_parent * jd.pose_child;
          offset_of[c] = Pose::Identity();
        }
        urdf_of[c] = make_body(m, d, jd.child_body, offset_of[c], child_name, s.tag);
        j.child = urdf_of[c];
        add_joint(std::move(j));
        stack.push_back(jd.child_body);
      }
    }
    auto link_pose = [&](const module_db::Connector& c) { return offset_of[static_cast<size_t>(c.body)] * c.pose; };
    // TCP / wheel-centre frames (massless) and the end-effector entry.
    const std::vector<int> tcps = d.tcp_connectors();
    for (size_t k = 0; k < tcps.size(); ++k) {
      const module_db::Connector& c = d.connectors[static_cast<size_t>(tcps[k])];
      const std::string word = d.type == ModuleType::kWheel ? "wheel" : "tcp";
      const std::string name = word + (k == 0 ? "" : std::to_string(k + 1)) + T;
      make_frame(m, urdf_of[static_cast<size_t>(c.body)], link_pose(c), name, s.tag);
      if (k == 0 && d.is_end_effector()) {
        EndEffectorInfo e;
        e.name = end_effector_word(d) + T;
        e.chain = s.tag;
        e.frame = name;
        e.module_key = d.key;
        e.kind = end_effector_kind(d);
        e.module = m;
        ees.push_back(std::move(e));
        if (ch != nullptr && ch->info.tip_link.empty()) ch->info.tip_link = name;
      }
    }
    for (const module_db::Frame& f : d.frames) {
      make_frame(m, urdf_of[static_cast<size_t>(f.body)], offset_of[static_cast<size_t>(f.body)] * f.pose, f.name + T, s.tag);
      if (const auto kind = sensor_kind(f.kind)) {
        model::SensorFrame sf;
        sf.name = f.name + T;
        sf.kind = *kind;
        sf.frame = f.name + T;
        sf.chain = s.tag;
        if (d.is_end_effector() && !tcps.empty()) sf.end_effector = end_effector_word(d) + T;
        sf.module_key = d.key;
        sensors.push_back(std::move(sf));
      }
    }
    // Children on output connectors, in connector order.
    std::vector<int> kids = children_[static_cast<size_t>(m)];
    std::sort(kids.begin(), kids.end(), [&](int a, int b) {
      const auto& na = tree_.modules[static_cast<size_t>(a)];
      const auto& nb = tree_.modules[static_cast<size_t>(b)];
      return std::tie(na.parent_connector, a) < std::tie(nb.parent_connector, b);
    });
    const std::vector<int> outs = d.output_connectors();
    std::set<int> used;
    for (int k : kids) {
      const auto& kn = tree_.modules[static_cast<size_t>(k)];
      const ModuleDescription& kd = *desc_[static_cast<size_t>(k)];
      const std::string who = module_label(kn, k);
      if (d.is_end_effector()) {
        throw ModelError(who + ": mounted on end-effector " + module_label(node, m) + ", which has no output connectors");
      }
      const int n = kn.parent_connector;
      if (n < 1 || n > static_cast<int>(outs.size())) {
        throw ModelError(who + ": parent " + module_label(node, m) + " has no output connector " + std::to_string(n) + " (it has " +
                         std::to_string(outs.size()) + ")");
      }
      if (!used.insert(n).second) {
        throw ModelError(who + ": output connector " + std::to_string(n) + " of " + module_label(node, m) + " is already used");
      }
      const int in = kd.input_connector();
      if (in < 0) throw ModelError(who + ": module '" + kd.key + "' has no input connector and cannot be mounted");
      const module_db::Connector& out_c = d.connectors[static_cast<size_t>(outs[static_cast<size_t>(n - 1)])];
      const module_db::Connector& in_c = kd.connectors[static_cast<size_t>(in)];
      if (out_c.size != in_c.size) {
        throw ModelError(who + ": connector size mismatch: input '" + in_c.name + "' is '" + in_c.size + "' but output connector " +
                         std::to_string(n) + " ('" + out_c.name + "') of " + module_label(node, m) + " is '" + out_c.size + "'");
      }
      expand(k, urdf_of[static_cast<size_t>(out_c.body)], link_pose(out_c), s, d.is_hub());
    }
  }

  const ModelGenerator& gen_;
  const topology::ModuleTree& tree_;
  std::vector<std::vector<int>> children_;
  std::vector<bool> visited_;
  std::set<std::string> names_;
  std::map<std::string, size_t> chain_index_;
  int next_tag_ = 0;
};

void apply_addons(const module_db::ModuleDatabase& db, const Customisation& custom, PhysicalTree& phi,
                  std::vector<EndEffectorInfo>& ees, std::vector<model::SensorFrame>& sensors,
                  const std::vector<const ModuleDescription*>& desc) {
  std::set<std::pair<int, std::string>> used_types;
  for (size_t i = 0; i < custom.addons.size(); ++i) {
    const AddonChoice& choice = custom.addons[i];
    const std::string where = "customisation addons[" + std::to_string(i) + "]";
    const module_db::AddonDescription* addon = db.find_addon(choice.addon);
    if (addon == nullptr) throw ModelError(where + ": unknown add-on '" + choice.addon + "'");
    int module = -1;
    EndEffectorInfo* ee = nullptr;
    for (EndEffectorInfo& e : ees) {
      if (e.name == choice.module_name) {
        ee = &e;
        module = e.module;
      }
    }
    if (ee == nullptr) {
      const int b = phi.body_index(choice.module_name);
      if (b < 0 || phi.bodies[static_cast<size_t>(b)].module < 0) {
        throw ModelError(where + ".module_name: no end-effector or body '" + choice.module_name + "'");
      }
      module = phi.bodies[static_cast<size_t>(b)].module;
      for (EndEffectorInfo& e : ees) {
        if (e.module == module) ee = &e;
      }
    }
    const ModuleDescription& d = *desc[static_cast<size_t>(module)];
    if (!d.addon_types.empty() &&
        std::find(d.addon_types.begin(), d.addon_types.end(), addon->type) == d.addon_types.end()) {
      throw ModelError(where + ": module '" + d.key + "' does not accept add-ons of type '" + addon->type + "'");
    }
    if (d.addon_types.empty()) {
      throw ModelError(where + ": module '" + d.key + "' accepts no add-ons");
    }
    if (!used_types.insert({module, addon->type}).second) {
      throw ModelError(where + ": module '" + d.key + "' already has a '" + addon->type + "' add-on");
    }
    if (ee == nullptr) throw ModelError(where + ": module '" + d.key + "' has no tool frame to mount '" + choice.addon + "' on");
    // The add-on hangs on the TCP frame: its mass joins the TCP's parent body, the TCP moves
    // along its z axis by the add-on's length, and sensor frames are added under the TCP.
    PhysicalJoint* tcp_joint = nullptr;
    const int tcp_body = phi.body_index(ee->frame);
    for (PhysicalJoint& j : phi.joints) {
      if (j.child == tcp_body) tcp_joint = &j;
    }
    PhysicalBody& host = phi.bodies[static_cast<size_t>(tcp_joint->parent)];
    const Pose tcp_pose = tcp_joint->origin;
    // A point mass: the files give no add-on inertia tensor.
    add_point_mass(host.inertial, addon->mass, tcp_pose * addon->com);
    tcp_joint->origin = tcp_pose * Eigen::Translation3d(0.0, 0.0, addon->tcp_offset);
    if (addon->frame) {
      PhysicalBody fb;
      fb.name = addon->frame->name + (ee->chain.empty() ? "" : "_" + ee->chain);
      if (phi.body_index(fb.name) >= 0) throw ModelError(where + ": frame '" + fb.name + "' exists already");
      fb.module = module;
      fb.chain = ee->chain;
      fb.massless = true;
      phi.bodies.push_back(fb);
      PhysicalJoint j;
      j.name = "fixed_" + fb.name;
      j.parent = tcp_body;
      j.child = static_cast<int>(phi.bodies.size()) - 1;
      j.origin = addon->frame->pose;
      j.module = module;
      j.chain = ee->chain;
      phi.joints.push_back(j);
      model::SensorFrame sf;
      sf.name = fb.name;
      sf.kind = sensor_kind(addon->frame->kind).value_or(model::SensorKind::kOther);
      sf.frame = fb.name;
      sf.chain = ee->chain;
      sf.end_effector = ee->name;
      sf.module_key = addon->key;
      sensors.push_back(std::move(sf));
    }
    ee->addons.push_back(choice.addon);
  }
}

}  // namespace

ModelGenerator::ModelGenerator(const module_db::ModuleDatabase& db, Params params) : db_(db), params_(std::move(params)) {}

const ModuleDescription& ModelGenerator::describe(const topology::ModuleNode& node) const {
  const ModuleDescription* d = nullptr;
  if (!node.key.empty()) {
    d = db_.find(node.key);
    // A key from another database's index (e.g. discovery ran on the public index): the ESC
    // identity still names the module type.
    if (d == nullptr && node.identity != topology::EscIdentity{}) d = db_.find_by_identity(node.identity);
    if (d == nullptr) {
      throw ModelError(module_label(node, node.index) + ": no module description with key '" + node.key + "' in the module database");
    }
    return *d;
  }
  d = db_.find_by_identity(node.identity);
  if (d == nullptr) {
    throw ModelError(module_label(node, node.index) + ": unknown ESC identity (mod_type " + std::to_string(node.identity.mod_type) +
                     ", mod_id " + std::to_string(node.identity.mod_id) + ", mod_size " + std::to_string(node.identity.mod_size) +
                     ", mod_rev " + std::to_string(node.identity.mod_rev) + ")");
  }
  return *d;
}

model::ModelDescription GeneratedModel::description() const {
  model::ModelDescription d;
  d.version = version;
  d.content_hash = content_hash;
  d.tree_version = tree_version;
  d.urdf = urdf;
  d.srdf = srdf;
  d.config_yaml = config_yaml;
  d.modules = modules;
  for (const JointInfo& j : joints) {
    d.joints.push_back({j.name, j.chain, j.lower, j.upper, j.velocity, j.peak_torque, j.continuous_torque});
  }
  for (const ChainInfo& c : chains) d.chains.push_back({c.name, c.role, c.base_link, c.tip_link, c.joints});
  for (const EndEffectorInfo& e : end_effectors) d.end_effectors.push_back({e.name, e.chain, e.frame, e.module_key, e.kind});
  d.sensor_frames = sensor_frames;
  return d;
}

PhysicalTree ModelGenerator::build_tree(const topology::ModuleTree& tree, const Customisation& custom) const {
  return generate(tree, custom).tree;
}

topology::ModuleTree ModelGenerator::mount_passive_modules(const topology::ModuleTree& tree, const Customisation& custom) const {
  topology::ModuleTree out = tree;
  bool any = false;
  for (const AddonChoice& c : custom.addons) {
    const ModuleDescription* d = db_.find_addon(c.addon) == nullptr ? db_.find(c.addon) : nullptr;
    if (d != nullptr) any = true;
  }
  if (!any) return out;
  // Names exist only once the tree is built: build it once to resolve module_name.
  Builder first(*this, tree);
  first.run();
  for (size_t i = 0; i < custom.addons.size(); ++i) {
    const AddonChoice& c = custom.addons[i];
    if (db_.find_addon(c.addon) != nullptr) continue;
    const ModuleDescription* d = db_.find(c.addon);
    const std::string where = "customisation addons[" + std::to_string(i) + "]";
    if (d == nullptr) continue;  // reported as an unknown add-on later
    if (d->esc) throw ModelError(where + ": module '" + c.addon + "' has an ESC and is discovered, not added by hand");
    int parent = -1;
    const int b = first.phi.body_index(c.module_name);
    if (b >= 0) {
      parent = first.phi.bodies[static_cast<size_t>(b)].module;
    } else {
      for (const ChainRecord& ch : first.chains) {
        if (ch.info.name == c.module_name && !ch.info.modules.empty()) parent = ch.info.modules.back();
      }
    }
    if (parent < 0) throw ModelError(where + ".module_name: no body or chain '" + c.module_name + "' to mount '" + c.addon + "' on");
    const ModuleDescription& pd = *first.desc_[static_cast<size_t>(parent)];
    std::set<int> used;
    for (const auto& n : out.modules) {
      if (n.parent_module == parent) used.insert(n.parent_connector);
    }
    int connector = 0;
    for (int k = 1; k <= static_cast<int>(pd.output_connectors().size()); ++k) {
      if (!used.count(k)) {
        connector = k;
        break;
      }
    }
    if (connector == 0) {
      throw ModelError(where + ": module '" + pd.key + "' (" + c.module_name + ") has no free output connector for '" + c.addon + "'");
    }
    topology::ModuleNode n;
    n.index = static_cast<int32_t>(out.modules.size());
    n.key = d->key;
    n.kind = topology::ModuleKind::kEndEffector;
    n.parent_module = parent;
    n.parent_connector = connector;
    out.modules.push_back(std::move(n));
  }
  return out;
}

void check_modelable(const topology::ModuleTree& tree) {
  std::string errors;
  std::size_t error_count = 0;
  for (const auto& issue : tree.issues) {
    if (issue.severity != topology::TreeIssue::Severity::kError) continue;
    if (error_count++ > 0) errors += "; ";
    errors += issue.text();
  }
  if (error_count > 0) {
    throw ModelError("the module tree has " + std::to_string(error_count) + " error" +
                     (error_count == 1 ? "" : "s") + " (" + errors +
                     "): no model is built from an undefined tree");
  }
  std::string unknown;
  std::size_t unknown_count = 0;
  for (const auto& m : tree.modules) {
    if (m.known) continue;
    if (unknown_count++ > 0) unknown += "; ";
    unknown += m.slave_positions.empty() ? "module #" + std::to_string(m.index)
                                         : "slave " + std::to_string(m.slave_positions.front());
    unknown += " " + topology::to_string(m.identity);
  }
  if (unknown_count > 0) {
    throw ModelError("the module tree has " + std::to_string(unknown_count) + " unknown module" +
                     (unknown_count == 1 ? "" : "s") +
                     ", not in the ESC catalogue of the module database: " + unknown +
                     "; no model is built until every module is known");
  }
}

GeneratedModel ModelGenerator::generate(const topology::ModuleTree& input_tree, const Customisation& input_custom,
                                    uint64_t tree_version) const {
  check_modelable(input_tree);
  // Passive modules without ESC (passive grippers) named in the add-ons are mounted first; the
  // remaining add-ons are applied to the built tree.
  const topology::ModuleTree tree = mount_passive_modules(input_tree, input_custom);
  Customisation custom_addons = input_custom;
  custom_addons.addons.clear();
  for (const AddonChoice& c : input_custom.addons) {
    const ModuleDescription* d = db_.find_addon(c.addon) == nullptr ? db_.find(c.addon) : nullptr;
    if (d == nullptr) custom_addons.addons.push_back(c);
  }
  const Customisation& custom = input_custom;
  Builder b(*this, tree);
  b.run();
  apply_addons(db_, custom_addons, b.phi, b.ees, b.sensors, b.desc_);
  GeneratedModel model;
  model.tree_version = tree_version;
  model.customisation = custom;
  model.tree = std::move(b.phi);
  model.end_effectors = std::move(b.ees);
  model.sensor_frames = std::move(b.sensors);
  for (size_t i = 0; i < tree.modules.size(); ++i) model.modules.push_back(b.desc_[i]->key);
  for (ChainRecord& c : b.chains) {
    using model::ChainRole;
    c.info.role = c.has_wheel ? ChainRole::kLeg : c.has_joint ? ChainRole::kArm : c.has_tool ? ChainRole::kTool : ChainRole::kOther;
    if (c.info.tip_link.empty()) c.info.tip_link = c.last_body;
    model.chains.push_back(std::move(c.info));
  }
  std::set<std::string> homed;
  for (const PhysicalJoint& j : model.tree.joints) {
    if (j.description == nullptr) continue;
    const module_db::JointDescription& jd = *j.description;
    JointInfo info;
    info.name = j.name;
    info.chain = j.chain;
    info.module = j.module;
    info.module_key = b.desc_[static_cast<size_t>(j.module)]->key;
    info.robot_id = tree.modules[static_cast<size_t>(j.module)].robot_id;
    info.type = jd.type;
    const double inf = std::numeric_limits<double>::infinity();
    info.lower = jd.type == JointType::kContinuous ? -inf : jd.limits.lower;
    info.upper = jd.type == JointType::kContinuous ? inf : jd.limits.upper;
    info.velocity = jd.limits.velocity;
    info.peak_torque = jd.limits.peak_torque;
    info.continuous_torque = jd.limits.continuous_torque.value_or(jd.limits.peak_torque);
    info.gear_ratio = jd.gear_ratio;
    info.gains = jd.control;
    const bool wheel = b.desc_[static_cast<size_t>(j.module)]->type == ModuleType::kWheel;
    info.control_mode = !jd.control.mode.empty() ? jd.control.mode : wheel ? "velocity" : "impedance";
    if (info.control_mode == "impedance" && info.gains.stiffness == 0.0) {
      info.gains.stiffness = params_.default_stiffness;
      info.gains.damping = params_.default_damping;
    }
    if (info.control_mode == "position" && info.gains.kp == 0.0) {
      info.gains.kp = params_.default_kp;
      info.gains.kd = params_.default_kd;
    }
    if (info.control_mode == "velocity" && info.gains.kp == 0.0) info.gains.kp = params_.default_velocity_kp;
    info.gains.mode = info.control_mode;
    info.home = std::clamp(0.0, info.lower, info.upper);
    auto it = custom.home.find(j.name);
    if (it != custom.home.end()) {
      if (!std::isfinite(it->second) || it->second < info.lower || it->second > info.upper) {
        throw ModelError("customisation home: " + j.name + " = " + std::to_string(it->second) + " is outside the limits [" +
                         std::to_string(info.lower) + ", " + std::to_string(info.upper) + "]");
      }
      info.home = it->second;
      homed.insert(j.name);
    }
    model.joints.push_back(std::move(info));
  }
  for (const auto& [name, value] : custom.home) {
    if (!homed.count(name)) throw ModelError("customisation home: no moving joint '" + name + "' in this robot");
  }
  model.urdf = write_urdf(model.tree, params_.robot_name);
  // A first SRDF: the posture search reads its disabled collision pairs; the final one carries
  // the posture chosen.
  model.srdf = write_srdf(model, params_.robot_name);
  try {
    model.resting = choose_resting_posture(model, homed, params_.home_torque_fraction);
  } catch (const std::exception& e) {
    throw ModelError(std::string("homing posture: ") + e.what());
  }
  model.srdf = write_srdf(model, params_.robot_name);
  model.config_yaml = write_config_yaml(model, params_.robot_name);
  std::string canonical = model.urdf;
  canonical += '\0';
  canonical += model.srdf;
  canonical += '\0';
  canonical += model.config_yaml;
  model.content_hash = sha256_hex(canonical);
  return model;
}

}  // namespace concert::model_generation
