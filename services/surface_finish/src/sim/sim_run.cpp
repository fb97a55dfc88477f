#include "surface_finish/sim_run.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <map>

#include "concert/model_generation/generator.hpp"
#include "concert/module_db/module_db.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "concert/world/world.hpp"
#include "sim_robot.hpp"

namespace concert::surface_finish {

namespace {

world::World wall_world(double face_x) {
  world::World w;
  world::WorldShape wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.2, 6.0, 3.2);
  wall.position = Eigen::Vector3d(face_x + 0.1, 0.0, 1.6);
  w.walls.push_back(wall);
  return w;
}

}  // namespace

namespace detail {

SimRobot load_sim_robot(const std::filesystem::path& assembly, const std::vector<std::filesystem::path>& module_dbs) {
  if (module_dbs.empty()) throw FinishError("simulated run: no module database");
  const sim::AssemblyBuilder builder(module_dbs);
  SimRobot out{builder.build(assembly), nullptr};
  const module_db::ModuleDatabase db = module_db::load_module_database(module_dbs.front());
  model_generation::GeneratedModel generated = model_generation::ModelGenerator(db).generate(out.robot.tree);
  generated.version = 1;
  out.model = model::RobotModel::build(generated.description());
  return out;
}

void position_commands(const std::vector<int>& index, const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref,
                       const Eigen::VectorXd& gravity, std::vector<hardware::DriveCommand>& cmd) {
  for (std::size_t i = 0; i < index.size(); ++i) {
    cmd[i] = hardware::DriveCommand{};
    cmd[i].mode = hardware::DriveMode::kPosition;
    if (index[i] < 0) continue;
    cmd[i].position = q_ref[index[i]];
    cmd[i].velocity = qd_ref[index[i]];
    cmd[i].effort = gravity[index[i]];
  }
}

}  // namespace detail

SprayRunResult run_spray_in_sim(const SprayRunParams& params) {
  const auto wall_clock = std::chrono::steady_clock::now();
  if (params.module_dbs.empty()) throw FinishError("spray run: no module database");
  if (params.rects.empty()) throw FinishError("spray run: no rectangle to spray");
  const detail::SimRobot loaded = detail::load_sim_robot(params.assembly, params.module_dbs);
  const sim::SimulatedRobot& robot = loaded.robot;
  const auto& model = loaded.model;
  Reach reach(model, model::EndEffectorKind::kSpraying);
  SprayRunResult result;

  double distance = params.wall_distance;
  if (!std::isfinite(distance)) distance = working_areas(reach, Task::kSpray, params.tool.standoff, params.areas).wall_distance;

  sim::SimParams sp;
  sp.sensors.enabled = false;
  sim::SimHardware hw(robot.urdf, wall_world(distance), sp);
  const std::vector<std::string> names = hw.joint_names();
  const kinematics::Model& k = model->kinematics();
  std::vector<int> index(names.size(), -1);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (auto j = k.joint_index(names[i])) index[i] = *j;
  }
  hardware::HardwareState state;
  std::vector<hardware::DriveCommand> cmd(names.size());
  kinematics::Data data = k.make_data();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(k.dof());
  const double dt = 0.001;
  auto read = [&] {
    hw.read(state);
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (index[i] >= 0) q[index[i]] = state.position[i];
    }
  };
  // Holds (q_ref, qd_ref) with gravity feed-forward for one step.
  auto drive = [&](const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref) {
    detail::position_commands(index, q_ref, qd_ref, k.gravity_torques(data, q), cmd);
    hw.write(cmd);
    hw.step(dt);
    read();
  };
  read();
  const Eigen::VectorXd q_hold = q;
  for (int i = 0; i < 500; ++i) drive(q_hold, Eigen::VectorXd::Zero(k.dof()));

  // The wall in the base frame from the simulator's truth (the wall face at x = distance).
  const Eigen::Isometry3d base0 = hw.base_pose();
  const Eigen::Isometry3d inv = base0.inverse();
  const WallFrame wall = WallFrame::from_plane(inv * Eigen::Vector3d(distance, base0.translation().y(), 0.0),
                                               inv.linear() * -Eigen::Vector3d::UnitX(), base0.translation().z());
  result.areas = compute_areas(reach, wall, Task::kSpray, params.tool.standoff, params.areas);
  const Area& area = result.areas.area(params.area);

  for (std::size_t r = 0; r < params.rects.size(); ++r) {
    const Rect rect = reshape(area, params.rects[r]);
    const auto strokes = serpentine_strokes(rect, params.tool, params.path.visible);
    const SerpentinePlan plan = plan_serpentine(reach, wall, rect, params.tool, result.areas.roll, params.path, q,
                                                &result.areas.posture_near(strokes.front().x, strokes.front().y_start));
    SprayDeposition dep(wall, rect, params.tool, params.path.speed, static_cast<int>(plan.strokes.size()));
    const auto& s = plan.samples;
    std::size_t kk = 0;
    const double end = plan.duration();
    Eigen::VectorXd q_ref(k.dof()), qd_ref(k.dof());
    for (double t = 0.0; t < end + 0.3; t += dt) {
      while (kk + 2 < s.size() && s[kk + 1].t <= t) ++kk;
      const PathSample& a = s[kk];
      const PathSample& b = s[std::min(kk + 1, s.size() - 1)];
      const double u = b.t > a.t ? std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0) : 1.0;
      q_ref = a.q + u * (b.q - a.q);
      qd_ref = t < end ? Eigen::VectorXd(a.qd + u * (b.qd - a.qd)) : Eigen::VectorXd::Zero(k.dof());
      drive(q_ref, qd_ref);
      const Eigen::Isometry3d tcp = inv * hw.link_pose(reach.tcp_frame());
      if (b.tool_on && t < end && valve_open(plan.strokes[static_cast<std::size_t>(b.stroke)], wall.coordinates(tcp.translation()))) {
        dep.add(tcp, dt, b.stroke);
        Eigen::Isometry3d target = b.tcp;
        target.translation() = a.tcp.translation() + u * (b.tcp.translation() - a.tcp.translation());
        result.max_tcp_error = std::max(result.max_tcp_error, (tcp.translation() - target.translation()).norm());
        result.max_standoff_error =
            std::max(result.max_standoff_error, std::abs(wall.coordinates(tcp.translation()).z() - params.tool.standoff));
      }
      result.sim_time += dt;
    }
    std::vector<double> xs;
    std::vector<bool> ups;
    for (const Stroke& st : plan.strokes) {
      xs.push_back(st.x);
      ups.push_back(st.up());
    }
    result.reports.push_back(dep.measure(xs, ups));
    if (!params.output_stem.empty()) {
      const std::string stem = params.output_stem + "_" + std::to_string(r + 1);
      std::ofstream(stem + ".json") << SprayDeposition::to_json(result.reports.back()) << "\n";
      dep.write_png(stem + ".png");
    }
    result.plans.push_back(plan);
  }
  result.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_clock).count();
  return result;
}

}  // namespace concert::surface_finish
