#include "resting_posture.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "concert/collision/link_shapes.hpp"
#include "concert/kinematics/model.hpp"
#include "concert/model/robot_model.hpp"

namespace concert::model_generation {

namespace {

constexpr double kPi = std::numbers::pi;

// One arm as the search sees it: its moving joints (indices into the kinematics model and
// into model.joints), which of them the search may move, and the frames that must stay above
// the arm's mount.
struct Arm {
  std::vector<int> q_index;         // kinematics joint index, root to tip
  std::vector<std::size_t> info;    // index into GeneratedModel::joints
  std::vector<bool> free;           // not homed by the customisation
  std::vector<std::string> frames;  // links moved by the arm's first joint
  std::string mount;                // the parent link of the arm's first joint
};

// Candidate positions of one joint: the database's zero first, then every 45 degrees over one
// turn and the joint's limits, within its limits (a prismatic joint: zero and its limits).
std::vector<double> candidates(const JointInfo& j) {
  std::vector<double> c{std::clamp(0.0, j.lower, j.upper)};
  if (j.type != module_db::JointType::kPrismatic) {
    for (int k = -4; k <= 4; ++k) c.push_back(k * kPi / 4.0);
  }
  if (std::isfinite(j.lower)) c.push_back(j.lower);
  if (std::isfinite(j.upper)) c.push_back(j.upper);
  std::vector<double> out;
  for (double v : c) {
    if (v < j.lower || v > j.upper) continue;
    if (std::none_of(out.begin(), out.end(), [v](double o) { return std::abs(o - v) < 1e-9; })) out.push_back(v);
  }
  return out;
}

}  // namespace

RestingPosture choose_resting_posture(GeneratedModel& model, const std::set<std::string>& homed,
                                      double fraction) {
  RestingPosture out;
  const kinematics::Model k = kinematics::Model::from_urdf_string(model.urdf);
  kinematics::Data data = k.make_data();
  std::map<std::string, std::size_t> info_of;
  for (std::size_t i = 0; i < model.joints.size(); ++i) info_of[model.joints[i].name] = i;

  std::vector<Arm> arms;
  for (const ChainInfo& c : model.chains) {
    if (c.role != concert::model::ChainRole::kArm || c.joints.empty()) continue;
    Arm arm;
    for (const std::string& name : c.joints) {
      arm.q_index.push_back(k.joint_index_or_throw(name));
      arm.info.push_back(info_of.at(name));
      arm.free.push_back(homed.count(name) == 0);
    }
    arm.frames = k.subtree_links(arm.q_index.front());
    arm.mount = k.joint_parent_link(arm.q_index.front());
    arms.push_back(std::move(arm));
  }

  Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
  for (const JointInfo& j : model.joints) q[k.joint_index_or_throw(j.name)] = j.home;

  // Static load of each arm joint: |gravity torque| / continuous torque. The largest one and
  // the joint carrying it.
  const auto loads = [&](const Eigen::VectorXd& at, std::string* worst) {
    const Eigen::VectorXd g = k.gravity_torques(data, at);
    double largest = 0.0;
    double sum4 = 0.0;
    for (const Arm& arm : arms) {
      for (std::size_t a = 0; a < arm.q_index.size(); ++a) {
        const JointInfo& j = model.joints[arm.info[a]];
        if (!(j.continuous_torque > 0.0)) continue;
        const double load = std::abs(g[arm.q_index[a]]) / j.continuous_torque;
        sum4 += load * load * load * load;
        if (load > largest) {
          largest = load;
          if (worst != nullptr) *worst = j.name;
        }
      }
    }
    return std::pair{largest, sum4};
  };
  // Metres by which the lowest frame moved by an arm sits more than 5 cm below that arm's mount
  // (0: none); a tool may hang a little below it.
  const auto below_mount = [&](const Eigen::VectorXd& at) {
    double below = 0.0;
    for (const Arm& arm : arms) {
      const double mount_z = k.frame_pose(data, at, arm.mount).translation().z();
      for (const std::string& f : arm.frames) {
        below = std::max(below, mount_z - k.frame_pose(data, at, f).translation().z());
      }
    }
    return std::max(0.0, below - 0.05);
  };

  // Self collision, with the shapes and disabled pairs every service checks (libs/collision):
  // the arm must not rest folded into itself or the base.
  const auto robot = concert::model::RobotModel::build(model.description());
  std::vector<std::string> arm_joint_names;
  for (const Arm& arm : arms) {
    for (std::size_t a = 0; a < arm.info.size(); ++a) arm_joint_names.push_back(model.joints[arm.info[a]].name);
  }
  collision::LinkShapes shapes(*robot, collision::rigid_groups(*robot, arm_joint_names));
  std::vector<Eigen::Isometry3d> poses(robot->links().size(), Eigen::Isometry3d::Identity());
  const auto collides = [&](const Eigen::VectorXd& at) {
    for (int l : shapes.links_with_shapes()) {
      poses[static_cast<std::size_t>(l)] = k.frame_pose(data, at, robot->links()[static_cast<std::size_t>(l)].name);
    }
    shapes.place(poses);
    return shapes.self_collision().has_value();
  };

  std::string worst;
  out.static_load = loads(q, &worst).first;
  out.joint = worst;
  if (out.static_load <= fraction) return out;  // the database's zero posture holds: keep it

  // Coordinate descent over each free joint's candidates. The cost is the sum of the loads'
  // fourth powers (the largest load dominates, and the search still moves when a joint other
  // than the largest one improves), plus a large penalty per metre an arm reaches below its
  // mount (into the base or the floor) and a larger one for a self collision, plus a small one
  // for leaving the zero posture.
  const auto cost = [&](const Eigen::VectorXd& at) {
    double travel = 0.0;
    for (const Arm& arm : arms) {
      for (int i : arm.q_index) travel += std::abs(at[i]);
    }
    return loads(at, nullptr).second + 100.0 * below_mount(at) + (collides(at) ? 1e3 : 0.0) + 1e-6 * travel;
  };
  const Eigen::VectorXd start = q;
  double best = cost(q);
  // Each free joint in turn tries `values(joint, current)`; a move that lowers the cost stays.
  const auto descend = [&](const auto& values, int sweeps) {
    for (int sweep = 0; sweep < sweeps; ++sweep) {
      bool improved = false;
      for (const Arm& arm : arms) {
        for (std::size_t a = 0; a < arm.q_index.size(); ++a) {
          if (!arm.free[a]) continue;
          const int i = arm.q_index[a];
          for (double v : values(model.joints[arm.info[a]], q[i])) {
            const double before = q[i];
            q[i] = v;
            const double c = cost(q);
            if (c < best - 1e-12) {
              best = c;
              improved = true;
            } else {
              q[i] = before;
            }
          }
        }
      }
      if (!improved) break;
    }
  };
  // Coarse: every 45 degrees and the limits. Then finer steps either side of where each joint
  // is (22.5 degrees down to under 3), which the coarse grid steps over.
  descend([](const JointInfo& j, double) { return candidates(j); }, 8);
  for (double step = kPi / 8.0; step > 0.04; step /= 2.0) {
    descend(
        [step](const JointInfo& j, double at) {
          std::vector<double> near;
          for (double v : {at - step, at + step}) {
            if (v >= j.lower && v <= j.upper) near.push_back(v);
          }
          return near;
        },
        8);
  }
  for (const Arm& arm : arms) {
    for (std::size_t a = 0; a < arm.q_index.size(); ++a) model.joints[arm.info[a]].home = q[arm.q_index[a]];
  }
  out.moved = q != start;
  out.static_load = loads(q, &worst).first;
  out.joint = worst;
  return out;
}

std::string describe(const RestingPosture& resting, double fraction) {
  const auto percent = [](double share) { return std::to_string(static_cast<int>(std::lround(100.0 * share))) + " %"; };
  if (resting.joint.empty() || (!resting.moved && resting.static_load <= fraction)) return "";
  std::string out = "homing posture: ";
  if (resting.moved) out += "the database's zero posture overloads the arm's drives, so the arm rests raised; ";
  out += resting.joint + " holds it with " + percent(resting.static_load) + " of its continuous torque";
  if (resting.static_load > fraction) {
    out += ", above the " + percent(fraction) +
           " the generator aims for: motion from there may reach the drive's thermal limit, where the safety layer "
           "stops the robot";
  }
  return out;
}

}  // namespace concert::model_generation
