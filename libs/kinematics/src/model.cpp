#include "concert/kinematics/model.hpp"

#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <kdl/jacobian.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>
#include <kdl/treejnttojacsolver.hpp>
#include <sstream>
#include <unordered_map>

#include "concert/common/text.hpp"
#include "urdf_to_kdl.hpp"

namespace concert::kinematics {

struct Model::Impl {
  std::string name;
  std::string urdf;
  std::string root_link;
  detail::KdlConversion kdl;
  std::unordered_map<std::string, int> joint_index;
  Eigen::Vector3d gravity;
};

// Each Data owns a copy of the model's KDL tree, and its solvers work on that copy alone. KDL's
// Joint::pose caches the last position and pose in mutable members, so a tree is written by every
// solve. TreeIdSolver_RNE keeps a reference to the tree it is given: on the model's own tree,
// two threads with their own Data both wrote its joints' caches, and a Data made meanwhile
// copied a cache torn between two positions; its forward kinematics then returned the pose of
// another position (kinematics_test's DataPerThreadGivesSameResults, once in a CI run).
struct Data::Impl {
  explicit Impl(std::shared_ptr<const Model::Impl> m)
      : model(std::move(m)),
        tree(model->kdl.tree),
        fk(tree),
        jac_solver(tree),
        id(tree, KDL::Vector(model->gravity.x(), model->gravity.y(), model->gravity.z())),
        q(model->kdl.tree.getNrOfJoints()),
        qd(model->kdl.tree.getNrOfJoints()),
        qdd(model->kdl.tree.getNrOfJoints()),
        tau(model->kdl.tree.getNrOfJoints()),
        jac(model->kdl.tree.getNrOfJoints()) {}
  std::shared_ptr<const Model::Impl> model;
  KDL::Tree tree;  // this Data's own: the solvers below write its joints' caches
  KDL::TreeFkSolverPos_recursive fk;
  KDL::TreeJntToJacSolver jac_solver;
  KDL::TreeIdSolver_RNE id;
  KDL::JntArray q, qd, qdd, tau;
  KDL::Jacobian jac;
  KDL::WrenchMap wrenches;
};

namespace {

void check_size(const Model::Impl& m, const Eigen::VectorXd& v, const char* what) {
  if (v.size() != static_cast<Eigen::Index>(m.kdl.joint_names.size())) {
    throw ModelError(std::string("model '") + m.name + "': " + what + " has size " + std::to_string(v.size()) +
                     ", expected " + std::to_string(m.kdl.joint_names.size()));
  }
}

void check_frame(const Model::Impl& m, std::string_view frame) {
  if (m.kdl.tree.getSegments().find(std::string(frame)) == m.kdl.tree.getSegments().end()) {
    throw ModelError("model '" + m.name + "': unknown frame '" + std::string(frame) + "'");
  }
}

// KDL's tree solvers read q(i) for every segment on the way, fixed ones included (at index 0),
// which is out of bounds for a tree without moving joints (a robot of passive modules only):
// Debian's KDL then fails an assertion and aborts the process (a tests/fuzz regression). Such a
// tree is composed here instead: the pose of each fixed segment, up to the root.
bool has_no_joint(const Model::Impl& m) { return m.kdl.tree.getNrOfJoints() == 0; }

KDL::Frame fixed_tree_pose(const KDL::Tree& tree, const std::string& frame) {
  KDL::Frame pose = KDL::Frame::Identity();
  for (auto it = tree.getSegments().find(frame); it != tree.getRootSegment();
       it = GetTreeElementParent(it->second)) {
    pose = GetTreeElementSegment(it->second).pose(0.0) * pose;
  }
  return pose;
}

/// Forward kinematics of `frame` at d.q (a frame of the model); false if KDL fails.
bool pose_at(const Model::Impl& m, Data::Impl& d, const std::string& frame, KDL::Frame& out) {
  if (has_no_joint(m)) {
    out = fixed_tree_pose(d.tree, frame);
    return true;
  }
  return d.fk.JntToCart(d.q, out, frame) >= 0;
}

/// Jacobian of `frame` at d.q into d.jac; without moving joints it has no column.
bool jacobian_at(const Model::Impl& m, Data::Impl& d, const std::string& frame) {
  return has_no_joint(m) || d.jac_solver.JntToJac(d.q, d.jac, frame) >= 0;
}

Eigen::Isometry3d to_eigen(const KDL::Frame& f) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out.linear()(r, c) = f.M(static_cast<unsigned>(r), static_cast<unsigned>(c));
    }
    out.translation()(r) = f.p(static_cast<unsigned>(r));
  }
  return out;
}

}  // namespace

Model::Model(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

Model Model::from_urdf_string(const std::string& urdf_xml, const ModelOptions& options) {
  // TinyXML 2.6.2, which urdfdom parses with, skips a multi-byte UTF-8 character by the length
  // its lead byte announces, past the end of the text when the character is cut short there: a
  // heap over-read (a tests/fuzz regression). Text that is not UTF-8 is refused before.
  if (const auto at = invalid_utf8_at(urdf_xml)) {
    throw ModelError("URDF is not valid UTF-8 (byte " + std::to_string(*at) + ")");
  }
  const urdf::ModelInterfaceSharedPtr parsed = urdf::parseURDF(urdf_xml);
  if (!parsed) {
    throw ModelError("URDF could not be parsed (malformed XML, missing links or joints; see urdfdom messages)");
  }
  auto impl = std::make_shared<Impl>();
  impl->name = parsed->getName();
  impl->urdf = urdf_xml;
  impl->root_link = parsed->getRoot() ? parsed->getRoot()->name : std::string{};
  impl->kdl = detail::urdf_to_kdl(*parsed, options);
  impl->gravity = options.gravity;
  for (std::size_t i = 0; i < impl->kdl.joint_names.size(); ++i) {
    impl->joint_index.emplace(impl->kdl.joint_names[i], static_cast<int>(i));
  }
  // KDL numbers joints in insertion order; the converter inserts depth-first, as listed.
  for (const auto& [name, element] : impl->kdl.tree.getSegments()) {
    const auto& joint = GetTreeElementSegment(element).getJoint();
    if (joint.getType() != KDL::Joint::None &&
        impl->joint_index.at(joint.getName()) != static_cast<int>(GetTreeElementQNr(element))) {
      throw ModelError("internal: KDL joint numbering differs for joint '" + joint.getName() + "'");
    }
  }
  return Model(std::move(impl));
}

Model Model::from_urdf_file(const std::string& path, const ModelOptions& options) {
  std::ifstream in(path);
  if (!in) {
    throw ModelError("cannot open URDF file '" + path + "'");
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  try {
    return from_urdf_string(buffer.str(), options);
  } catch (const ModelError& e) {
    throw ModelError("URDF file '" + path + "': " + e.what());
  }
}

const std::string& Model::name() const { return impl_->name; }
int Model::dof() const { return static_cast<int>(impl_->kdl.joint_names.size()); }
const std::vector<std::string>& Model::joint_names() const { return impl_->kdl.joint_names; }
const std::vector<JointLimits>& Model::joint_limits() const { return impl_->kdl.joint_limits; }
const std::vector<JointType>& Model::joint_types() const { return impl_->kdl.joint_types; }

std::optional<int> Model::joint_index(std::string_view joint) const {
  const auto it = impl_->joint_index.find(std::string(joint));
  if (it == impl_->joint_index.end()) {
    return std::nullopt;
  }
  return it->second;
}

int Model::joint_index_or_throw(std::string_view joint) const {
  if (auto i = joint_index(joint)) {
    return *i;
  }
  std::string known;
  for (const auto& n : impl_->kdl.joint_names) {
    known += (known.empty() ? "" : ", ") + n;
  }
  throw ModelError("model '" + impl_->name + "': unknown joint '" + std::string(joint) + "' (known: " + known + ")");
}

bool Model::is_virtual_joint(int index) const { return index >= 0 && index < impl_->kdl.num_virtual_joints; }
int Model::num_virtual_joints() const { return impl_->kdl.num_virtual_joints; }
const std::vector<std::string>& Model::frame_names() const { return impl_->kdl.frame_names; }
bool Model::has_frame(std::string_view frame) const {
  return impl_->kdl.tree.getSegments().count(std::string(frame)) > 0;
}
const std::string& Model::root_link() const { return impl_->root_link; }
const std::string& Model::joint_parent_link(int index) const { return impl_->kdl.joint_parent_links.at(index); }
const std::string& Model::joint_child_link(int index) const { return impl_->kdl.joint_child_links.at(index); }
const Eigen::Vector3d& Model::joint_axis(int index) const { return impl_->kdl.joint_axes.at(index); }

std::vector<std::string> Model::subtree_links(int index) const {
  std::vector<std::string> out;
  const auto& segments = impl_->kdl.tree.getSegments();
  std::function<void(KDL::SegmentMap::const_iterator)> visit = [&](KDL::SegmentMap::const_iterator it) {
    out.push_back(it->first);
    for (const auto& child : GetTreeElementChildren(it->second)) {
      visit(child);
    }
  };
  visit(segments.find(joint_child_link(index)));
  return out;
}

std::vector<int> Model::descendant_joints(int index) const {
  std::vector<int> out;
  const auto& segments = impl_->kdl.tree.getSegments();
  for (const auto& link : subtree_links(index)) {
    const auto& element = segments.find(link)->second;
    if (GetTreeElementSegment(element).getJoint().getType() != KDL::Joint::None) {
      const int q = static_cast<int>(GetTreeElementQNr(element));
      if (q != index) {
        out.push_back(q);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

double Model::total_mass() const { return impl_->kdl.total_mass; }
const Eigen::Vector3d& Model::gravity() const { return impl_->gravity; }
const std::string& Model::urdf() const { return impl_->urdf; }

Data Model::make_data() const { return Data(impl_); }

Eigen::Isometry3d Model::frame_pose(Data& data, const Eigen::VectorXd& q, std::string_view frame) const {
  check_size(*impl_, q, "q");
  check_frame(*impl_, frame);
  auto& d = *data.impl_;
  d.q.data = q;
  KDL::Frame out;
  if (!pose_at(*impl_, d, std::string(frame), out)) {
    throw ModelError("model '" + impl_->name + "': forward kinematics failed for frame '" + std::string(frame) + "'");
  }
  return to_eigen(out);
}

Eigen::Isometry3d Model::relative_pose(Data& data, const Eigen::VectorXd& q, std::string_view reference,
                                       std::string_view frame) const {
  return frame_pose(data, q, reference).inverse() * frame_pose(data, q, frame);
}

Eigen::MatrixXd Model::frame_jacobian(Data& data, const Eigen::VectorXd& q, std::string_view frame) const {
  check_size(*impl_, q, "q");
  check_frame(*impl_, frame);
  auto& d = *data.impl_;
  d.q.data = q;
  // KDL: reference point at the frame origin, expressed in the root ("world") frame.
  if (!jacobian_at(*impl_, d, std::string(frame))) {
    throw ModelError("model '" + impl_->name + "': Jacobian failed for frame '" + std::string(frame) + "'");
  }
  return d.jac.data;
}

Eigen::VectorXd Model::gravity_torques(Data& data, const Eigen::VectorXd& q) const {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(dof());
  return inverse_dynamics(data, q, zero, zero);
}

Eigen::VectorXd Model::inverse_dynamics(Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                        const Eigen::VectorXd& qdd,
                                        const std::map<std::string, Eigen::Matrix<double, 6, 1>>& external) const {
  check_size(*impl_, q, "q");
  check_size(*impl_, qd, "qd");
  check_size(*impl_, qdd, "qdd");
  auto& d = *data.impl_;
  d.q.data = q;
  d.qd.data = qd;
  d.qdd.data = qdd;
  d.wrenches.clear();
  for (const auto& [frame, w] : external) {
    check_frame(*impl_, frame);
    if (frame == "world") {
      continue;
    }
    KDL::Frame pose;
    (void)pose_at(*impl_, d, frame, pose);
    // KDL wants the wrench in the segment frame, reference point at the segment origin.
    const KDL::Wrench world_aligned(KDL::Vector(w(0), w(1), w(2)), KDL::Vector(w(3), w(4), w(5)));
    d.wrenches[frame] = pose.M.Inverse(world_aligned);
  }
  if (d.id.CartToJnt(d.q, d.qd, d.qdd, d.wrenches, d.tau) < 0) {
    throw ModelError("model '" + impl_->name + "': inverse dynamics failed");
  }
  return d.tau.data;
}

void Model::frame_pose_into(Data& data, const Eigen::VectorXd& q, const std::string& frame,
                            Eigen::Isometry3d& out) const {
  auto& d = *data.impl_;
  d.q.data = q;
  KDL::Frame f;
  (void)pose_at(*impl_, d, frame, f);
  out = to_eigen(f);
}

void Model::frame_jacobian_into(Data& data, const Eigen::VectorXd& q, const std::string& frame,
                                Eigen::MatrixXd& out) const {
  auto& d = *data.impl_;
  d.q.data = q;
  (void)jacobian_at(*impl_, d, frame);
  out = d.jac.data;
}

void Model::inverse_dynamics_into(Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                  const Eigen::VectorXd& qdd, Eigen::VectorXd& out) const {
  auto& d = *data.impl_;
  d.q.data = q;
  d.qd.data = qd;
  d.qdd.data = qdd;
  d.wrenches.clear();
  d.id.CartToJnt(d.q, d.qd, d.qdd, d.wrenches, d.tau);
  out = d.tau.data;
}

Eigen::MatrixXd Model::mass_matrix(Data& data, const Eigen::VectorXd& q) const {
  const int n = dof();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd g = inverse_dynamics(data, q, zero, zero);
  Eigen::MatrixXd m(n, n);
  Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j) {
    e.setZero();
    e(j) = 1.0;
    m.col(j) = inverse_dynamics(data, q, zero, e) - g;
  }
  return m;
}

IkResult Model::inverse_kinematics(Data& data, std::string_view frame, const Eigen::Isometry3d& target,
                                   const Eigen::VectorXd& seed, const IkOptions& options) const {
  check_size(*impl_, seed, "seed");
  check_frame(*impl_, frame);
  std::vector<int> joints = options.joints;
  if (joints.empty()) {
    for (int j = 0; j < dof(); ++j) {
      const auto sub = subtree_links(j);
      if (std::find(sub.begin(), sub.end(), std::string(frame)) != sub.end()) {
        joints.push_back(j);
      }
    }
  }
  for (int j : joints) {
    if (j < 0 || j >= dof()) {
      throw ModelError("model '" + impl_->name + "': IK joint index " + std::to_string(j) + " out of range");
    }
  }
  const int rows = options.position_only ? 3 : 6;
  const auto m = static_cast<Eigen::Index>(joints.size());
  IkResult result;
  result.q = seed;
  for (result.iterations = 0; result.iterations <= options.max_iterations; ++result.iterations) {
    const Eigen::Isometry3d pose = frame_pose(data, result.q, frame);
    Eigen::Matrix<double, 6, 1> error;
    error.head<3>() = target.translation() - pose.translation();
    const Eigen::AngleAxisd rot(target.linear() * pose.linear().transpose());
    error.tail<3>() = rot.angle() * rot.axis();
    result.position_error = error.head<3>().norm();
    result.orientation_error = options.position_only ? 0.0 : error.tail<3>().norm();
    if (result.position_error <= options.position_tolerance &&
        result.orientation_error <= options.orientation_tolerance) {
      result.converged = true;
      break;
    }
    if (result.iterations == options.max_iterations || m == 0) {
      break;
    }
    const Eigen::MatrixXd full = frame_jacobian(data, result.q, frame);
    Eigen::MatrixXd jac(rows, m);
    for (Eigen::Index k = 0; k < m; ++k) {
      jac.col(k) = full.col(joints[static_cast<std::size_t>(k)]).head(rows);
    }
    const Eigen::MatrixXd jjt = jac * jac.transpose() +
                                options.damping * options.damping * Eigen::MatrixXd::Identity(rows, rows);
    Eigen::VectorXd step = jac.transpose() * jjt.ldlt().solve(error.head(rows));
    const double largest = step.cwiseAbs().maxCoeff();
    if (largest > options.max_step) {
      step *= options.max_step / largest;
    }
    for (Eigen::Index k = 0; k < m; ++k) {
      const int j = joints[static_cast<std::size_t>(k)];
      const auto& lim = impl_->kdl.joint_limits[static_cast<std::size_t>(j)];
      result.q(j) += step(k);
      if (lim.has_position_limits) {
        result.q(j) = std::clamp(result.q(j), lim.lower, lim.upper);
      }
    }
  }
  return result;
}

Data::Data(std::shared_ptr<const Model::Impl> model) : impl_(std::make_unique<Impl>(std::move(model))) {}
Data::Data(Data&&) noexcept = default;
Data& Data::operator=(Data&&) noexcept = default;
Data::~Data() = default;

}  // namespace concert::kinematics
