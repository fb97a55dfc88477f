#include "concert/sim/sim_hardware.hpp"

#include <mujoco/mujoco.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <iomanip>
#include <random>
#include <mutex>
#include <sstream>

#include "concert/mobile_base/base_kinematics.hpp"
#include "concert/hardware/realtime_buffer.hpp"
#include "concert/sim/geom_groups.hpp"
#include "concert/sim/imu_simulator.hpp"
#include "concert/sim/rgbd_renderer.hpp"
#include "mjcf_text.hpp"
#include "drilling_model.hpp"
#include "sensor_runtime.hpp"
#include "world_mjcf.hpp"

namespace concert::sim {

using hardware::DriveCommand;
using mjcf::num;
using mjcf::vec;
using hardware::DriveMode;
using hardware::HardwareError;
using hardware::HardwareState;
using hardware::MountedHardware;
using mobile_base::collision_cylinder_radii;
using mobile_base::detect_legs;
using mobile_base::Leg;

namespace {

urdf::ModelInterfaceSharedPtr parse(const std::string& urdf) {
  auto model = urdf::parseURDF(urdf);
  if (!model) {
    throw HardwareError("sim: the robot URDF could not be parsed");
  }
  return model;
}

std::string pos_quat(const urdf::Pose& p) {
  return "pos=\"" + vec(p.position.x, p.position.y, p.position.z) + "\" quat=\"" + num(p.rotation.w) + " " +
         vec(p.rotation.x, p.rotation.y, p.rotation.z) + "\"";
}

Eigen::Matrix3d rotation(const urdf::Rotation& r) { return Eigen::Quaterniond(r.w, r.x, r.y, r.z).toRotationMatrix(); }

struct MjcfWriter {
  const SimParams& params;
  const std::vector<SensorMount>& sensors;
  const std::map<std::string, double>& wheel_radii;
  std::ostringstream xml;
  std::vector<std::string> actuated;  // joint names in depth-first order
  std::vector<double> efforts;
  std::vector<std::string> assets;    // <mesh> elements
  int skipped_meshes{0};

  // package://NAME/rest, file://PATH or an absolute path -> existing file, else "".
  [[nodiscard]] std::string resolve(const std::string& uri) const {
    std::string path;
    if (uri.rfind("package://", 0) == 0) {
      const std::string rest = uri.substr(10);
      const auto slash = rest.find('/');
      const auto root = params.package_paths.find(rest.substr(0, slash));
      if (root == params.package_paths.end() || slash == std::string::npos) {
        return "";
      }
      path = root->second + "/" + rest.substr(slash + 1);
    } else if (uri.rfind("file://", 0) == 0) {
      path = uri.substr(7);
    } else if (!uri.empty() && uri.front() == '/') {
      path = uri;
    }
    std::error_code ec;
    return !path.empty() && std::filesystem::is_regular_file(path, ec) ? path : "";
  }

  void geoms(const urdf::Link& link, bool is_wheel) {
    int k = 0;
    for (const auto& c : link.collision_array) {
      if (!c || !c->geometry) {
        continue;
      }
      const std::string name = "\"" + link.name + "_collision_" + std::to_string(k++) + "\"";
      const auto own = params.link_friction.find(link.name);
      const double mu = own != params.link_friction.end() ? own->second
                        : is_wheel                         ? params.wheel_friction
                                                           : params.robot_friction;
      const std::string common = " name=" + name + " " + pos_quat(c->origin) + " group=\"" +
                                 std::to_string(houses_camera(link) ? kCameraHousingGeomGroup : kRobotGeomGroup) +
                                 "\" contype=\"1\" conaffinity=\"0\"" + " friction=\"" + num(mu) +
                                 " 0.005 0.0001\"" +
                                 (own != params.link_friction.end() ? " priority=\"1\"" : "");
      switch (c->geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& b = dynamic_cast<const urdf::Box&>(*c->geometry);
          xml << "<geom type=\"box\" size=\"" << vec(b.dim.x / 2, b.dim.y / 2, b.dim.z / 2) << "\"" << common
              << "/>\n";
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& cy = dynamic_cast<const urdf::Cylinder&>(*c->geometry);
          xml << "<geom type=\"cylinder\" size=\"" << num(cy.radius) << " " << num(cy.length / 2) << "\"" << common
              << "/>\n";
          break;
        }
        case urdf::Geometry::SPHERE: {
          const auto& s = dynamic_cast<const urdf::Sphere&>(*c->geometry);
          xml << "<geom type=\"sphere\" size=\"" << num(s.radius) << "\"" << common << "/>\n";
          break;
        }
        case urdf::Geometry::MESH: {
          // Wheels roll on their cylinder: a convex hull of the tyre mesh would not.
          const auto& mesh = dynamic_cast<const urdf::Mesh&>(*c->geometry);
          const std::string file = resolve(mesh.filename);
          if (is_wheel || file.empty()) {
            ++skipped_meshes;
            break;
          }
          const std::string asset = "mesh_" + std::to_string(assets.size());
          assets.push_back("<mesh name=\"" + asset + "\" file=\"" + file + "\" scale=\"" +
                           vec(mesh.scale.x, mesh.scale.y, mesh.scale.z) + "\"/>");
          xml << "<geom type=\"mesh\" mesh=\"" << asset << "\"" << common << "/>\n";
          break;
        }
        default:
          break;
      }
    }
  }

  void inertial(const urdf::Link& link) {
    if (!link.inertial || link.inertial->mass <= 0.0) {
      return;
    }
    const auto& in = *link.inertial;
    Eigen::Matrix3d i;
    i << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    const Eigen::Matrix3d r = rotation(in.origin.rotation);
    const Eigen::Matrix3d il = r * i * r.transpose();
    // Principal axes; module databases contain rank-deficient inertias (e.g. point-mass
    // tools), which MuJoCo refuses: clamp the principal moments to a small positive value.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(il);
    Eigen::Matrix3d axes = eig.eigenvectors();
    if (axes.determinant() < 0.0) {
      axes.col(2) = -axes.col(2);
    }
    const Eigen::Vector3d moments = eig.eigenvalues().cwiseMax(1e-6 * std::max(in.mass, 1e-3));
    const Eigen::Quaterniond q(axes);
    xml << "<inertial pos=\"" << vec(in.origin.position.x, in.origin.position.y, in.origin.position.z)
        << "\" quat=\"" << num(q.w()) << " " << vec(q.x(), q.y(), q.z()) << "\" mass=\"" << num(in.mass)
        << "\" diaginertia=\"" << vec(moments.x(), moments.y(), moments.z()) << "\"/>\n";
  }

  void joint(const urdf::Joint& j) {
    if (j.type == urdf::Joint::FIXED) {
      return;
    }
    if (j.type != urdf::Joint::REVOLUTE && j.type != urdf::Joint::CONTINUOUS && j.type != urdf::Joint::PRISMATIC) {
      throw HardwareError("sim: URDF joint '" + j.name + "' has a type MuJoCo cannot take here (floating/planar)");
    }
    const bool slide = j.type == urdf::Joint::PRISMATIC;
    xml << "<joint name=\"" << j.name << "\" type=\"" << (slide ? "slide" : "hinge") << "\" axis=\""
        << vec(j.axis.x, j.axis.y, j.axis.z) << "\" armature=\"" << num(params.armature) << "\"";
    if (j.type != urdf::Joint::CONTINUOUS && j.limits && j.limits->upper > j.limits->lower) {
      xml << " limited=\"true\" range=\"" << num(j.limits->lower) << " " << num(j.limits->upper) << "\"";
    } else {
      xml << " limited=\"false\"";
    }
    if (j.dynamics) {
      xml << " damping=\"" << num(j.dynamics->damping * params.damping_scale) << "\" frictionloss=\""
          << num(j.dynamics->friction * params.friction_scale) << "\"";
    }
    xml << "/>\n";
    actuated.push_back(j.name);
    efforts.push_back(j.limits ? j.limits->effort : 0.0);
  }

  /// True if a camera is mounted on a frame fixed to `link` (its geoms are the camera's housing).
  [[nodiscard]] bool houses_camera(const urdf::Link& link) const {
    for (const auto& s : sensors) {
      if (s.type != hardware::SensorType::kRgbd) {
        continue;
      }
      for (const auto& child : link.child_links) {
        if (child->name == s.frame) {
          return true;
        }
      }
    }
    return false;
  }

  /// A site for each IMU mounted at `link` (its MuJoCo gyro and accelerometer read there).
  void imu_sites(const std::string& link) {
    for (const auto& s : sensors) {
      if (s.type == hardware::SensorType::kImu && s.frame == link) {
        xml << imu_mjcf(imu_site_name(s.name)).site;
      }
    }
  }

  /// The <sensor> section: gyro and accelerometer of each IMU (read by the sensor threads).
  [[nodiscard]] std::string imu_sensors() const {
    std::string out;
    for (const auto& s : sensors) {
      if (s.type == hardware::SensorType::kImu) {
        out += imu_mjcf(imu_site_name(s.name)).sensors;
      }
    }
    return out.empty() ? out : "<sensor>\n" + out + "</sensor>\n";
  }

  void body(const urdf::Link& link) {
    for (const auto& child : link.child_links) {
      const urdf::Joint& j = *child->parent_joint;
      xml << "<body name=\"" << child->name << "\" " << pos_quat(j.parent_to_joint_origin_transform) << ">\n";
      inertial(*child);
      imu_sites(child->name);
      joint(j);
      geoms(*child, wheel_radii.count(child->name) > 0 && j.type != urdf::Joint::FIXED);
      body(*child);
      xml << "</body>\n";
    }
  }
};

struct Built {
  std::string mjcf;
  int meshes{0};
  std::vector<std::string> joints;
  bool floating{false};
  std::string root;  ///< the root link's body (world bodies, e.g. moving obstacles, come first)
  std::vector<std::string> leg_joints;  ///< every steering and wheel joint of the mobile base
};

/// The steering legs of the robot: by role when the robot names them, else (a bare URDF, which
/// carries no roles) by their axes.
std::vector<Leg> robot_legs(const kinematics::Model& model, const std::string& urdf,
                            const std::optional<std::vector<SimLeg>>& by_role) {
  if (!by_role) return detect_legs(model, collision_cylinder_radii(urdf));
  std::vector<Leg> legs;
  for (const SimLeg& leg : *by_role) {
    try {
      legs.push_back(mobile_base::measure_leg(model, leg.steering_joint, leg.wheel_joint, leg.wheel_radius));
    } catch (const std::exception& e) {
      throw HardwareError("sim: leg " + leg.steering_joint + "/" + leg.wheel_joint + ": " + e.what());
    }
  }
  return legs;
}

Built build_mjcf(const std::string& urdf, const World& world, const SimParams& params,
                 const std::vector<SensorMount>& sensors, const std::optional<std::vector<SimLeg>>& by_role) {
  const auto parsed = parse(urdf);
  for (const auto& [link, mu] : params.link_friction) {
    if (!parsed->getLink(link)) {
      throw HardwareError("sim: link_friction names '" + link + "', which is no link of the robot");
    }
    if (!(mu >= 0.0) || !std::isfinite(mu)) {
      throw HardwareError("sim: link_friction of '" + link + "' must be a finite friction >= 0");
    }
  }
  const kinematics::Model model = kinematics::Model::from_urdf_string(urdf);
  std::vector<Leg> legs = robot_legs(model, urdf, by_role);
  std::map<std::string, double> wheel_links;
  Built out;
  for (const auto& leg : legs) {
    wheel_links[model.joint_child_link(model.joint_index_or_throw(leg.wheel_joint))] = leg.wheel_radius;
    out.leg_joints.push_back(leg.steering_joint);
    out.leg_joints.push_back(leg.wheel_joint);
  }
  out.floating = params.floating_base.value_or(!legs.empty());
  double z = params.base_position.z();
  if (out.floating && !legs.empty()) {
    z = world.floor_height + mobile_base::standing_height(legs) + 0.002;
  }
  MjcfWriter w{params, sensors, wheel_links, {}, {}, {}, {}, 0};
  const urdf::Link& root = *parsed->getRoot();
  out.root = root.name;
  w.xml << "<worldbody>\n";
  const WorldMjcf world_xml = world_mjcf(world);
  w.xml << world_xml.worldbody;
  w.xml << "<body name=\"" << root.name << "\" pos=\"" << vec(params.base_position.x(), params.base_position.y(), z)
        << "\" euler=\"0 0 " << num(params.base_yaw) << "\">\n";
  if (out.floating) {
    w.xml << "<freejoint name=\"__floating_base\"/>\n";
  }
  w.inertial(root);
  w.imu_sites(root.name);
  w.geoms(root, false);
  w.body(root);
  w.xml << "</body>\n</worldbody>\n<actuator>\n";
  for (std::size_t i = 0; i < w.actuated.size(); ++i) {
    w.xml << "<general name=\"" << w.actuated[i] << "\" joint=\"" << w.actuated[i]
          << "\" gaintype=\"fixed\" gainprm=\"1\" biastype=\"affine\" biasprm=\"0 0 0\" ctrllimited=\"false\"";
    if (w.efforts[i] > 0.0) {
      w.xml << " forcelimited=\"true\" forcerange=\"" << num(-w.efforts[i]) << " " << num(w.efforts[i]) << "\"";
    }
    w.xml << "/>\n";
  }
  w.xml << "</actuator>\n" << w.imu_sensors() << "</mujoco>\n";
  std::ostringstream head;
  head << "<mujoco model=\"" << parsed->getName() << "\">\n"
       << "<compiler angle=\"radian\" inertiafromgeom=\"false\" boundmass=\"0.0001\" boundinertia=\"0.00000001\" "
          "balanceinertia=\"true\"/>\n"
       << visual_mjcf(params.sensors.camera)
       << "<option timestep=\"" << num(params.timestep) << "\" integrator=\"implicit\" gravity=\"0 0 -9.81\"/>\n";
  if (!w.assets.empty() || !world_xml.assets.empty()) {
    head << "<asset>\n" << world_xml.assets;
    for (const auto& a : w.assets) {
      head << a << "\n";
    }
    head << "</asset>\n";
  }
  out.mjcf = head.str() + w.xml.str();
  out.meshes = static_cast<int>(w.assets.size());
  out.joints = w.actuated;
  return out;
}

}  // namespace

std::string urdf_to_mjcf(const std::string& urdf, const World& world, const SimParams& params) {
  return build_mjcf(urdf, world, params, {}, std::nullopt).mjcf;
}

/// One MuJoCo robot in one world: what a hot swap or a world change prepares off the control
/// thread and the control thread switches to.
struct Instance {
  Instance() = default;
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;
  ~Instance() {
    if (d != nullptr) {
      mj_deleteData(d);
    }
    if (m != nullptr) {
      mj_deleteModel(m);
    }
  }
  std::string urdf;
  World world;
  Built built;
  mjModel* m{nullptr};
  mjData* d{nullptr};
  ObstacleMotion obstacles;  ///< moves the world's moving obstacles (mocap bodies)
  std::vector<int> qpos_adr, dof_adr;
  /// Per actuated joint: its module's identity (SimulatedRobot::joint_modules; empty for a bare
  /// URDF), its homing position and its range (-inf, inf without limits).
  std::vector<std::string> module_of;
  std::vector<double> home, lower, upper;
  std::vector<DriveCommand> commands;
  std::vector<double> rated_effort;  ///< each actuator's forcerange from the URDF (0: none)
  std::uint64_t generation{0};
  std::vector<SensorMount> sensors;
  std::vector<DrillBit> drill_bits;
  DrillingModel drilling;
  /// What the sensor threads read (null when the sensors are off).
  std::shared_ptr<SensorScene> scene;
  /// Only the world changed: the running instance's whole state carries over.
  bool same_robot{false};
  int root_body{-1};  ///< MuJoCo body of the URDF root
  std::vector<int> leg_dofs;  ///< the legs' steering and wheel joints' dof addresses
  int still_steps{0};         ///< physics steps since a leg joint last moved (stand_grip)
};

namespace {

std::unique_ptr<Instance> make_instance(const SimulatedRobot& robot, const World& world,
                                        const SimParams& robot_params) {
  const std::string& urdf = robot.urdf;
  const std::vector<SensorMount>& sensors = robot.sensors;
  const std::vector<DrillBit>& drill_bits = robot.drill_bits;
  const std::vector<std::string>& sanding_links = robot.sanding_links;
  world::validate_world(world, "sim world");
  // The running sanding disc's friction on the sanding tools' links (link_friction wins).
  SimParams params = robot_params;
  if (params.sanding_disc_friction >= 0.0) {
    for (const std::string& link : sanding_links)
      params.link_friction.emplace(link, params.sanding_disc_friction);
  }
  auto in = std::make_unique<Instance>();
  in->built = build_mjcf(urdf, world, params, sensors, robot.legs);
  in->sensors = sensors;
  in->urdf = urdf;
  in->world = world;
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  const char* file = "robot.xml";
  if (mj_makeEmptyFileVFS(&vfs, file, static_cast<int>(in->built.mjcf.size())) != 0) {
    throw HardwareError("sim: could not allocate the MuJoCo virtual file");
  }
  std::memcpy(vfs.filedata[0], in->built.mjcf.data(), in->built.mjcf.size());
  char error[1000] = "";
  in->m = mj_loadXML(file, &vfs, error, sizeof(error));
  mj_deleteVFS(&vfs);
  if (in->m == nullptr) {
    throw HardwareError(std::string("sim: MuJoCo rejected the model built from the URDF: ") + error);
  }
  fill_world_hfields(world, in->m);
  in->obstacles = ObstacleMotion(world, in->m);
  in->drill_bits = drill_bits;
  in->drilling = DrillingModel(in->m, drill_bits, world, params.drilling);
  in->d = mj_makeData(in->m);
  in->obstacles.apply(in->d, 0.0);
  in->commands.assign(in->built.joints.size(), DriveCommand{});
  for (int a = 0; a < in->m->nu; ++a) {
    in->rated_effort.push_back(in->m->actuator_forcelimited[a] ? in->m->actuator_forcerange[2 * a + 1] : 0.0);
  }
  for (std::size_t i = 0; i < in->built.joints.size(); ++i) {
    const int jid = mj_name2id(in->m, mjOBJ_JOINT, in->built.joints[i].c_str());
    in->qpos_adr.push_back(in->m->jnt_qposadr[jid]);
    in->dof_adr.push_back(in->m->jnt_dofadr[jid]);
    const std::string& name = in->built.joints[i];
    const bool limited = in->m->jnt_limited[jid] != 0;
    in->lower.push_back(limited ? in->m->jnt_range[2 * jid] : -std::numeric_limits<double>::infinity());
    in->upper.push_back(limited ? in->m->jnt_range[2 * jid + 1] : std::numeric_limits<double>::infinity());
    const auto module = robot.joint_modules.find(name);
    in->module_of.push_back(module != robot.joint_modules.end() ? module->second : std::string());
    const auto home = robot.joint_homes.find(name);
    in->home.push_back(std::clamp(home != robot.joint_homes.end() ? home->second : 0.0, in->lower[i], in->upper[i]));
    double q = in->home[i];  // each module is new to the robot: its homing position
    if (auto p = params.initial_positions.find(name); p != params.initial_positions.end()) {
      q = p->second;
    }
    in->d->qpos[in->qpos_adr[i]] = q;
    in->commands[i].mode = DriveMode::kPosition;
    in->commands[i].position = q;
  }
  mj_forward(in->m, in->d);
  if (params.sensors.enabled) {
    in->scene = std::make_shared<SensorScene>(in->m, sensors, in->built.root, world.floor_height);
  }
  in->root_body = mj_name2id(in->m, mjOBJ_BODY, in->built.root.c_str());
  for (const std::string& j : in->built.leg_joints) {
    const int jid = mj_name2id(in->m, mjOBJ_JOINT, j.c_str());
    if (jid >= 0) in->leg_dofs.push_back(in->m->jnt_dofadr[jid]);
  }
  return in;
}

/// The joint of `from` that `to`'s joint i is, or -1: the same module (a hot swap can give a
/// kept module's joint another name, and a kept name to another module's joint); by name only
/// where either robot is a bare URDF, which names no modules.
int same_joint(const Instance& from, const Instance& to, std::size_t i) {
  for (std::size_t k = 0; k < from.built.joints.size(); ++k) {
    const bool by_name = to.module_of[i].empty() || from.module_of[k].empty();
    if (by_name ? from.built.joints[k] == to.built.joints[i] : from.module_of[k] == to.module_of[i]) {
      return static_cast<int>(k);
    }
  }
  return -1;
}

/// Carries the state of `from` into `to` (control thread, no allocation): for a new robot the
/// base pose and each joint of a kept module, within the joint's range; a joint whose module is
/// new starts at its homing position. Everything for a new world around the same robot.
void carry_state(const Instance& from, Instance& to) {
  to.d->time = from.d->time;
  to.obstacles.apply(to.d, to.d->time);
  if (to.same_robot && to.m->nq == from.m->nq && to.m->nv == from.m->nv) {
    std::copy_n(from.d->qpos, from.m->nq, to.d->qpos);
    std::copy_n(from.d->qvel, from.m->nv, to.d->qvel);
    std::copy_n(from.d->qacc_warmstart, from.m->nv, to.d->qacc_warmstart);
    std::copy(from.commands.begin(), from.commands.end(), to.commands.begin());
  } else {
    for (std::size_t i = 0; i < to.built.joints.size(); ++i) {
      const int k = same_joint(from, to, i);
      double q = to.home[i];
      if (k >= 0) {
        q = std::clamp(from.d->qpos[from.qpos_adr[static_cast<std::size_t>(k)]], to.lower[i], to.upper[i]);
        to.d->qvel[to.dof_adr[i]] = from.d->qvel[from.dof_adr[static_cast<std::size_t>(k)]];
      }
      to.d->qpos[to.qpos_adr[i]] = q;
      to.commands[i].position = q;
    }
    if (from.built.floating && to.built.floating) {
      std::copy_n(from.d->qpos, 7, to.d->qpos);
    }
  }
  mj_forward(to.m, to.d);
}

// MuJoCo's friction is soft: a contact below its friction limit still slides, at a speed in
// proportion to the force. For a rolling wheel that is much what a tyre does (its lateral force
// grows with the slip), but a base standing on its held wheels would creep under any push:
// 0.9 mm/s sideways under 150 N with 1000 N of friction to spare, 2.6 mm/s under 400 N (sim_test's
// HeldWheelsStandUnderAPushBelowFrictionAndSlideAboveIt), unseen by wheel odometry. A drill's
// thrust would walk the standing base back from the wall (holes 28.3-29.7 mm deep of 30 asked),
// and a pattern drilled by the kinematics alone would inherit every push of the alignment.
// A standing tyre grips: once no steering or wheel joint has moved for kStillTime, MuJoCo's
// no-slip pass (mjOption::noslip_iterations) removes the contacts' slip within their friction
// cones; a push above mu N still slides the base. Not stiff all the time (elliptic cones,
// impratio 100): then rolling wheels whose speeds disagree a little fight each other, the
// steering and wheel drives at their continuous torque, and a whole-body move misses its goal.
void stand_grip(Instance& in) {
  constexpr double kStill = 0.01;     // leg joint speeds below this: standing [rad/s]
  constexpr double kStillTime = 0.05;  // [s]
  constexpr int kNoslipIterations = 10;
  if (in.leg_dofs.empty()) return;
  bool still = true;
  for (const int dof : in.leg_dofs) still = still && std::abs(in.d->qvel[dof]) < kStill;
  in.still_steps = still ? in.still_steps + 1 : 0;
  in.m->opt.noslip_iterations = in.still_steps * in.m->opt.timestep >= kStillTime ? kNoslipIterations : 0;
}

}  // namespace

struct SimHardware::Impl {
  SimParams params;
  std::unique_ptr<Instance> active;  // control thread
  std::mt19937 rng;
  // Preparation side (any thread but the control thread): `preparing` serialises swaps and
  // world changes; `mutex` guards what they announce.
  std::mutex preparing;
  mutable std::mutex mutex;
  SimulatedRobot latest_robot;  // its urdf, sensors, drill bits, sanding links and legs
  World latest_world;
  // The sensors: the scene of the running instance (published by the control thread at each
  // switch) and the threads that read it (made on the first sink).
  std::atomic<std::shared_ptr<SensorScene>> active_scene;
  std::unique_ptr<SensorRuntime> sensor_runtime;
  MountedHardware mounted;
  hardware::Handover<Instance> prepared;
  // Ground truth of the base for other threads (base_truth()); the control thread only try-locks.
  mutable std::mutex truth_mutex;
  BaseTruth truth;
  // Holes (control thread) and the copy holes() returns (under truth_mutex, try-locked).
  std::vector<SimHole> holes;
  std::vector<SimHole> holes_copy;
  bool holes_dirty{false};
  // set_external_force(): body, force and point (world), applied at every physics step (control thread).
  std::string external_link;
  int external_body{-1};
  const Instance* external_instance{nullptr};  // the instance external_body was resolved on
  Eigen::Vector3d external_force{Eigen::Vector3d::Zero()};
  Eigen::Vector3d external_point{Eigen::Vector3d::Zero()};

  // MuJoCo's xfrc_applied acts at the body's centre of mass: the force at `point` adds the
  // moment (point - com) x force. Re-resolved after a swap; cleared if the link is gone.
  void apply_external_force() {
    if (external_link.empty()) return;
    Instance& in = *active;
    if (external_instance != &in) {
      external_body = mj_name2id(in.m, mjOBJ_BODY, external_link.c_str());
      external_instance = &in;
      if (external_body < 0) {
        external_link.clear();
        return;
      }
    }
    double* f = in.d->xfrc_applied + 6 * external_body;
    const double* com = in.d->xipos + 3 * external_body;
    const Eigen::Vector3d r = external_point - Eigen::Vector3d(com[0], com[1], com[2]);
    const Eigen::Vector3d moment = r.cross(external_force);
    for (int i = 0; i < 3; ++i) {
      f[i] = external_force[i];
      f[3 + i] = moment[i];
    }
  }

  // The simulated person (person()): orders queued by any thread under person_mutex, taken by
  // step() when it gets the lock (the control thread never waits); the person, its body and the
  // TCP's last position are the control thread's.
  std::mutex person_mutex;
  std::vector<world::PersonOrder> person_orders;
  world::SimPerson person_sim;
  std::string person_link;
  int person_body{-1};
  const Instance* person_instance{nullptr};
  Eigen::Vector3d person_last_tcp{Eigen::Vector3d::Zero()};
  bool person_fresh{true};  // no previous position to take the TCP's velocity from
  std::uint64_t person_taken{0};
  world::PersonReport person_copy;  // under truth_mutex
  // The held (or last held) link's body in the active instance, for the report's `tcp`: found
  // again when the instance or the link changes.
  int report_body{-1};
  const Instance* report_instance{nullptr};
  world::PersonPhase person_copied_phase{world::PersonPhase::kAbsent};

  void take_person_orders() {
    if (!person_mutex.try_lock()) return;
    std::vector<world::PersonOrder> orders;
    orders.swap(person_orders);
    person_mutex.unlock();
    for (const world::PersonOrder& o : orders) take_person_order(o);
  }

  void take_person_order(const world::PersonOrder& o) {
    ++person_taken;
    Instance& in = *active;
    switch (o.action) {
      case world::PersonOrder::Action::kGrip: {
        const int body = mj_name2id(in.m, mjOBJ_BODY, o.link.c_str());
        release_person_body();
        if (body < 0) {
          // Checked against the URDF; MuJoCo merges a fixed link into its parent.
          person_sim = world::SimPerson(o.params);
          person_link = o.link;
          person_sim.grip(in.d->time, Eigen::Vector3d::Zero());
          person_sim.let_go("no body '" + o.link + "' in the simulated robot (a fixed link merged into its parent?)");
          return;
        }
        person_sim = world::SimPerson(o.params);
        person_link = o.link;
        person_body = body;
        person_instance = &in;
        const Eigen::Vector3d tcp(in.d->xpos[3 * body], in.d->xpos[3 * body + 1], in.d->xpos[3 * body + 2]);
        person_sim.grip(in.d->time, tcp, o.guide, o.guide_time);
        report_instance = nullptr;
        person_last_tcp = tcp;
        person_fresh = false;
        return;
      }
      case world::PersonOrder::Action::kWalk: {
        if (!person_sim.gripping()) return;  // let go since the order was checked: nothing to walk
        std::vector<Eigen::Vector2d> route = o.route;
        if (o.relative) {
          for (Eigen::Vector2d& p : route) p += person_sim.hand().head<2>();
        }
        person_sim.walk(in.d->time, std::move(route));
        return;
      }
      case world::PersonOrder::Action::kRelease:
        person_sim.let_go("released");
        release_person_body();
        return;
    }
  }

  void release_person_body() {
    if (person_body >= 0 && person_instance == active.get() && person_body != external_body) {
      std::fill_n(active->d->xfrc_applied + 6 * person_body, 6, 0.0);
    }
    person_body = -1;
    person_instance = nullptr;
  }

  // The person's pull on its body for one physics step, added to a force the test put on the
  // same body (set_external_force), else in place of what was there.
  void apply_person() {
    if (!person_sim.gripping()) return;
    Instance& in = *active;
    if (person_instance != &in) {
      person_body = mj_name2id(in.m, mjOBJ_BODY, person_link.c_str());
      person_instance = &in;
      person_fresh = true;
      if (person_body < 0) {
        person_sim.let_go("the link '" + person_link + "' is gone from the simulated robot");
        person_instance = nullptr;
        return;
      }
    }
    const int b = person_body;
    const Eigen::Vector3d tcp(in.d->xpos[3 * b], in.d->xpos[3 * b + 1], in.d->xpos[3 * b + 2]);
    const double dt = in.m->opt.timestep;
    const Eigen::Vector3d velocity = person_fresh ? Eigen::Vector3d::Zero() : Eigen::Vector3d((tcp - person_last_tcp) / dt);
    person_last_tcp = tcp;
    person_fresh = false;
    const Eigen::Vector3d force = person_sim.force(in.d->time + dt, tcp, velocity);
    double* f = in.d->xfrc_applied + 6 * b;
    const bool shared = b == external_body && external_instance == &in && !external_link.empty();
    if (!shared) std::fill_n(f, 6, 0.0);
    if (!person_sim.gripping()) return;
    const double* com = in.d->xipos + 3 * b;
    const Eigen::Vector3d moment = (tcp - Eigen::Vector3d(com[0], com[1], com[2])).cross(force);
    for (int i = 0; i < 3; ++i) {
      f[i] += force[i];
      f[3 + i] += moment[i];
    }
  }

  // Under truth_mutex: the numbers every step, the strings only when the phase changes (the
  // control loop does not allocate in its steady state).
  void copy_person() {
    world::PersonReport& r = person_copy;
    if (person_sim.phase() != person_copied_phase || r.orders != person_taken) {
      r.link = person_link;
      r.reason = person_sim.reason();
      person_copied_phase = person_sim.phase();
    }
    r.phase = person_sim.phase();
    r.hand = person_sim.hand();
    // Where the link is now, also after the person let go (a lift or a placing is measured there).
    r.tcp = person_last_tcp;
    if (!person_link.empty()) {
      if (report_instance != active.get()) {
        report_body = mj_name2id(active->m, mjOBJ_BODY, person_link.c_str());
        report_instance = active.get();
      }
      if (report_body >= 0) {
        const double* x = active->d->xpos + 3 * report_body;
        r.tcp = Eigen::Vector3d(x[0], x[1], x[2]);
      }
    }
    r.pull = person_sim.pull();
    r.walked = person_sim.walked();
    r.route_length = person_sim.route_length();
    r.peak_pull = person_sim.peak_pull();
    r.time = active->d->time;
    r.orders = person_taken;
  }

  void submit(std::unique_ptr<Instance> in) { prepared.submit(std::move(in)); }

  void apply_drives() {
    Instance& in = *active;
    for (std::size_t i = 0; i < in.commands.size(); ++i) {
      const DriveCommand& c = in.commands[i];
      double kp = 0.0, kd = 0.0;
      switch (c.mode) {
        case DriveMode::kPosition:
          kp = params.position_stiffness;
          kd = params.position_damping;
          break;
        case DriveMode::kVelocity:
          kd = params.velocity_gain;
          break;
        case DriveMode::kEffort:
          break;
        case DriveMode::kImpedance:
          kp = std::max(0.0, c.stiffness);
          kd = std::max(0.0, c.damping);
          break;
      }
      const double ff = c.mode == DriveMode::kVelocity ? 0.0 : c.effort;
      const double pos_term = c.mode == DriveMode::kVelocity ? 0.0 : kp * c.position;
      // General actuator: force = ctrl + biasprm[1] q + biasprm[2] qd, saturated at forcerange.
      // The velocity-dependent part stays inside MuJoCo so the implicit integrator damps it stably.
      // The drive's torque limit this cycle: its rated peak, or less when the command says so.
      const double rated = in.rated_effort[i];
      const double limit = c.max_effort > 0.0 && (rated <= 0.0 || c.max_effort < rated) ? c.max_effort : rated;
      in.m->actuator_forcelimited[i] = limit > 0.0 ? 1 : 0;
      in.m->actuator_forcerange[2 * i] = -limit;
      in.m->actuator_forcerange[2 * i + 1] = limit;
      in.m->actuator_biasprm[i * mjNBIAS + 1] = -kp;
      in.m->actuator_biasprm[i * mjNBIAS + 2] = -kd;
      in.d->ctrl[i] = pos_term + kd * c.velocity + ff;
    }
  }
};

namespace {

SimulatedRobot bare(const std::string& urdf, std::vector<SensorMount> sensors, std::vector<DrillBit> drill_bits,
                    std::vector<std::string> sanding_links) {
  SimulatedRobot robot;
  robot.urdf = urdf;
  robot.sensors = std::move(sensors);
  robot.drill_bits = std::move(drill_bits);
  robot.sanding_links = std::move(sanding_links);
  return robot;
}

}  // namespace

SimHardware::SimHardware(const std::string& urdf, World world, SimParams params,
                         std::vector<SensorMount> sensors, std::vector<DrillBit> drill_bits,
                         std::vector<std::string> sanding_links)
    : SimHardware(bare(urdf, std::move(sensors), std::move(drill_bits), std::move(sanding_links)),
                  std::move(world), std::move(params)) {}

SimHardware::SimHardware(SimulatedRobot robot, World world, SimParams params) : impl_(std::make_unique<Impl>()) {
  impl_->params = std::move(params);
  impl_->rng.seed(impl_->params.seed);
  if (impl_->params.timestep <= 0.0) {
    throw HardwareError("sim: timestep must be positive");
  }
  impl_->active = make_instance(robot, world, impl_->params);
  impl_->active->generation = 1;
  impl_->latest_robot = std::move(robot);
  impl_->latest_world = std::move(world);
  impl_->mounted = {1, impl_->active->built.joints};
  impl_->active_scene.store(impl_->active->scene);
  if (impl_->params.sensors.enabled) {
    impl_->sensor_runtime = std::make_unique<SensorRuntime>(impl_->params.sensors, impl_->active_scene);
  }
}

SimHardware::~SimHardware() {
  impl_->sensor_runtime.reset();  // joins the sensor threads before the scenes go
}

void SimHardware::set_sensor_sink(hardware::SensorSink* sink) {
  if (impl_->sensor_runtime) {
    impl_->sensor_runtime->set_sink(sink);
  }
}

std::vector<hardware::SensorInfo> SimHardware::sensors() const {
  std::vector<hardware::SensorInfo> out;
  if (!impl_->params.sensors.enabled) {
    return out;
  }
  std::lock_guard lock(impl_->mutex);
  for (const SensorMount& m : impl_->latest_robot.sensors) {
    out.push_back({m.name, m.type, m.frame, sensor_rate(impl_->params.sensors, m.type)});
  }
  return out;
}

const std::vector<std::string>& SimHardware::joint_names() const { return impl_->active->built.joints; }
std::uint64_t SimHardware::generation() const { return impl_->active->generation; }

MountedHardware SimHardware::mounted() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->mounted;
}

std::uint64_t SimHardware::mounted_generation() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->mounted.generation;
}

bool SimHardware::switch_prepared() {
  Instance* next = impl_->prepared.take();
  if (next == nullptr) {
    return false;
  }
  carry_state(*impl_->active, *next);
  if (!next->same_robot && impl_->person_sim.gripping()) {
    impl_->person_sim.let_go("hot swap: the robot changed");
    impl_->person_body = -1;
    impl_->person_instance = nullptr;
  }
  Instance* old = impl_->active.release();
  impl_->active.reset(next);
  // The old scene stays referenced by the retired instance (deleted off this thread).
  impl_->active_scene.store(next->scene);
  if (!impl_->prepared.retire(old)) {
    delete old;  // unreachable in practice: each preparation collects the retired instance first
  }
  return true;
}

void SimHardware::read(HardwareState& state) {
  const Instance& in = *impl_->active;
  const auto n = in.built.joints.size();
  state.time = in.d->time;
  state.position.resize(n);
  state.velocity.resize(n);
  state.effort.resize(n);
  std::normal_distribution<double> pos_noise(0.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    state.position[i] = in.d->qpos[in.qpos_adr[i]];
    state.velocity[i] = in.d->qvel[in.dof_adr[i]];
    state.effort[i] = in.d->actuator_force[i];
    if (impl_->params.position_noise > 0.0) {
      state.position[i] += impl_->params.position_noise * pos_noise(impl_->rng);
    }
    if (impl_->params.effort_noise > 0.0) {
      state.effort[i] += impl_->params.effort_noise * pos_noise(impl_->rng);
    }
  }
}

void SimHardware::write(const std::vector<DriveCommand>& commands) {
  Instance& in = *impl_->active;
  if (commands.size() != in.built.joints.size()) {
    throw HardwareError("sim: " + std::to_string(commands.size()) + " drive commands for " +
                        std::to_string(in.built.joints.size()) + " joints");
  }
  std::copy(commands.begin(), commands.end(), in.commands.begin());
}

void SimHardware::step(double dt) {
  const int n = std::max(1, static_cast<int>(std::lround(dt / impl_->params.timestep)));
  impl_->take_person_orders();
  for (int k = 0; k < n; ++k) {
    impl_->apply_drives();
    impl_->apply_external_force();
    impl_->apply_person();
    impl_->active->obstacles.apply(impl_->active->d, impl_->active->d->time);
    if (!impl_->active->drilling.empty() &&
        impl_->active->drilling.apply(impl_->active->m, impl_->active->d, impl_->holes)) {
      impl_->holes_dirty = true;
    }
    stand_grip(*impl_->active);
    mj_step(impl_->active->m, impl_->active->d);
  }
  if (impl_->active->scene) {
    impl_->active->scene->publish(impl_->active->d);
  }
  if (impl_->active->root_body >= 0 && impl_->truth_mutex.try_lock()) {
    const int root = impl_->active->root_body;
    const mjData* d = impl_->active->d;
    impl_->truth.time = d->time;
    for (int r = 0; r < 3; ++r) {
      impl_->truth.pose.translation()(r) = d->xpos[3 * root + r];
      for (int c = 0; c < 3; ++c) impl_->truth.pose.linear()(r, c) = d->xmat[9 * root + 3 * r + c];
    }
    if (impl_->holes_dirty) {
      impl_->holes_copy = impl_->holes;  // allocates only when a hole opened or deepened
      impl_->holes_dirty = false;
    }
    impl_->copy_person();
    impl_->truth_mutex.unlock();
  }
  // As on real drives, measured efforts and contacts lag the positions by one physics step
  // (mj_step computes forces before integrating); a second mj_forward would double the cost.
}

bool SimHardware::swap_model(const std::string& urdf, std::vector<SensorMount> sensors,
                             std::vector<DrillBit> drill_bits,
                             std::vector<std::string> sanding_links) {
  return swap_model(bare(urdf, std::move(sensors), std::move(drill_bits), std::move(sanding_links)));
}

bool SimHardware::swap_model(SimulatedRobot robot) {
  // Preparations are serialised (each builds on the latest robot and world); mounted() and
  // world() stay answerable meanwhile, as they only take `mutex`.
  std::lock_guard preparing(impl_->preparing);
  World world;
  {
    std::lock_guard lock(impl_->mutex);
    if (robot.urdf == impl_->latest_robot.urdf) {
      return false;  // the same robot was mounted again: no hardware change
    }
    world = impl_->latest_world;
  }
  auto next = make_instance(robot, world, impl_->params);
  std::lock_guard lock(impl_->mutex);
  next->generation = impl_->mounted.generation + 1;
  impl_->latest_robot = std::move(robot);
  impl_->mounted = {next->generation, next->built.joints};
  impl_->submit(std::move(next));
  return true;
}

void SimHardware::set_world(const World& world) {
  std::lock_guard preparing(impl_->preparing);
  SimulatedRobot robot;
  {
    std::lock_guard lock(impl_->mutex);
    robot = impl_->latest_robot;
  }
  auto next = make_instance(robot, world, impl_->params);
  next->same_robot = true;
  std::lock_guard lock(impl_->mutex);
  next->generation = impl_->mounted.generation;  // same robot: no new hardware generation
  impl_->latest_world = world;
  impl_->submit(std::move(next));
}

World SimHardware::world() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->latest_world;
}

void SimHardware::set_external_force(const std::string& link, const Eigen::Vector3d& force,
                                     const Eigen::Vector3d& point) {
  if (!force.allFinite() || !point.allFinite()) {
    throw HardwareError("sim: external force on '" + link + "': non-finite force or point");
  }
  Instance& in = *impl_->active;
  const int id = mj_name2id(in.m, mjOBJ_BODY, link.c_str());
  if (id < 0) {
    throw HardwareError("sim: external force on unknown link '" + link + "'");
  }
  if (impl_->external_body >= 0 && impl_->external_instance == &in && impl_->external_body != id) {
    std::fill_n(in.d->xfrc_applied + 6 * impl_->external_body, 6, 0.0);  // the previous body lets go
  }
  impl_->external_link = link;
  impl_->external_body = id;
  impl_->external_instance = &in;
  impl_->external_force = force;
  impl_->external_point = point;
}

void SimHardware::clear_external_force() {
  Instance& in = *impl_->active;
  if (impl_->external_body >= 0 && impl_->external_instance == &in) {
    std::fill_n(in.d->xfrc_applied + 6 * impl_->external_body, 6, 0.0);
  }
  impl_->external_link.clear();
  impl_->external_body = -1;
  impl_->external_instance = nullptr;
}

std::string SimHardware::person(const world::PersonOrder& order) {
  std::ostringstream what;
  what.setf(std::ios::fixed);
  what.precision(2);
  world::PersonOrder o = order;
  if (o.action == world::PersonOrder::Action::kGrip) {
    try {
      world::check(o.params);
    } catch (const std::invalid_argument& e) {
      throw HardwareError(std::string("sim: ") + e.what());
    }
    if (!o.guide.allFinite() || !std::isfinite(o.guide_time) || o.guide_time < 0.0)
      throw HardwareError("sim: person: grip: the guide must be finite and its time >= 0");
    std::lock_guard lock(impl_->mutex);
    const std::vector<std::string>& grippers = impl_->latest_robot.gripper_tcps;
    if (o.link.empty()) {
      if (grippers.size() != 1) {
        std::string all;
        for (const std::string& g : grippers) all += (all.empty() ? "" : ", ") + g;
        throw HardwareError(grippers.empty()
                                ? "sim: person: the mounted robot has no gripper to hold; name a link"
                                : "sim: person: the mounted robot has " + std::to_string(grippers.size()) +
                                      " grippers (" + all + "); name the link to hold");
      }
      o.link = grippers.front();
    } else if (impl_->latest_robot.urdf.find("<link name=\"" + o.link + "\"") == std::string::npos) {
      throw HardwareError("sim: person: no link '" + o.link + "' in the mounted robot");
    }
    what << "person: gripping " << o.link;
    if (o.guide_time > 0.0)
      what << ", guiding it by (" << o.guide.x() << ", " << o.guide.y() << ", " << o.guide.z() << ") m over "
           << o.guide_time << " s";
  } else if (o.action == world::PersonOrder::Action::kWalk) {
    if (o.route.empty()) throw HardwareError("sim: person: walk: the route has no point");
    for (const Eigen::Vector2d& p : o.route) {
      if (!p.allFinite()) throw HardwareError("sim: person: walk: a route point is not finite");
    }
    bool pending_grip = false;
    {
      std::lock_guard lock(impl_->person_mutex);
      for (const world::PersonOrder& q : impl_->person_orders) pending_grip = q.action == world::PersonOrder::Action::kGrip;
    }
    const world::PersonReport now = person_report();
    const bool holding = now.phase != world::PersonPhase::kAbsent && now.phase != world::PersonPhase::kLetGo;
    if (!holding && !pending_grip)
      throw HardwareError("sim: person: walk: the person holds nothing (" +
                          std::string(now.phase == world::PersonPhase::kLetGo ? "let go: " + now.reason : "grip first") + ")");
    double length = 0.0;
    Eigen::Vector2d last = o.relative ? Eigen::Vector2d::Zero() : o.route.front();
    for (const Eigen::Vector2d& p : o.route) {
      length += (p - last).norm();
      last = p;
    }
    what << "person: walking " << (o.relative ? "" : "at least ") << length << " m through " << o.route.size()
         << " point" << (o.route.size() == 1 ? "" : "s");
  } else {
    what << "person: letting go";
  }
  std::lock_guard lock(impl_->person_mutex);
  impl_->person_orders.push_back(std::move(o));
  return what.str();
}

world::PersonReport SimHardware::person_report() const {
  std::lock_guard lock(impl_->truth_mutex);
  return impl_->person_copy;
}

double SimHardware::time() const { return impl_->active->d->time; }

Eigen::Isometry3d SimHardware::link_pose(const std::string& link) const {
  const int id = mj_name2id(impl_->active->m, mjOBJ_BODY, link.c_str());
  if (id < 0) {
    throw HardwareError("sim: unknown link '" + link + "'");
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    pose.translation()(r) = impl_->active->d->xpos[3 * id + r];
    for (int c = 0; c < 3; ++c) {
      pose.linear()(r, c) = impl_->active->d->xmat[9 * id + 3 * r + c];
    }
  }
  return pose;
}

Eigen::Isometry3d SimHardware::base_pose() const { return link_pose(impl_->active->built.root); }

SimHardware::BaseTruth SimHardware::base_truth() const {
  std::lock_guard lock(impl_->truth_mutex);
  return impl_->truth;
}

std::vector<SimHole> SimHardware::holes() const {
  std::lock_guard lock(impl_->truth_mutex);
  return impl_->holes_copy;
}

Eigen::Vector3d SimHardware::contact_force_on(const std::vector<std::string>& links) const {
  std::vector<int> bodies;
  for (const auto& l : links) {
    const int id = mj_name2id(impl_->active->m, mjOBJ_BODY, l.c_str());
    if (id < 0) {
      throw HardwareError("sim: unknown link '" + l + "'");
    }
    bodies.push_back(id);
  }
  auto on_robot = [&](int geom) {
    return std::find(bodies.begin(), bodies.end(), impl_->active->m->geom_bodyid[geom]) != bodies.end();
  };
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int i = 0; i < impl_->active->d->ncon; ++i) {
    const mjContact& c = impl_->active->d->contact[i];
    const bool g1 = on_robot(c.geom1), g2 = on_robot(c.geom2);
    if (g1 == g2) {
      continue;
    }
    mjtNum f[6];
    mj_contactForce(impl_->active->m, impl_->active->d, i, f);
    // Contact frame rows: normal (from geom1 to geom2), then tangents; the force acts on geom2.
    Eigen::Vector3d world = Eigen::Vector3d::Zero();
    for (int r = 0; r < 3; ++r) {
      world += f[r] * Eigen::Vector3d(c.frame[3 * r], c.frame[3 * r + 1], c.frame[3 * r + 2]);
    }
    total += g2 ? world : Eigen::Vector3d(-world);
  }
  return total;
}

const std::string& SimHardware::mjcf() const { return impl_->active->built.mjcf; }
const std::string& SimHardware::urdf() const { return impl_->active->urdf; }
bool SimHardware::floating_base() const { return impl_->active->built.floating; }

}  // namespace concert::sim
