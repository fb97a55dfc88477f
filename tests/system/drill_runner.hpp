#pragma once
// A drilling mission on a whole simulated stack, judged against the simulator's truth: shared by
// the drilling system test and its benchmark (bench_drill_mission). Every service is a process
// (safety, discovery, modelgen, the robot with MuJoCo and the cameras' noise, planner, drill);
// the holes are the ones the simulator's wall records (concert/sim/holes), the targets the marks'
// true positions (libs/world) and the patterns laid on the markers' true poses.

#include <Eigen/Geometry>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "concert/bim/model.hpp"
#include "concert/bim/storey_map.hpp"
#include "concert/bim/storey_world.hpp"
#include "concert/bim/wall_goal.hpp"
#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "concert/mobile_base/map_frame.hpp"
#include "concert/world/geometry.hpp"
#include "concert/world/world.hpp"
#include "drill/patterns.hpp"
#include "helpers.hpp"
#include "process.hpp"

namespace concert::system_test {

/// A drilled hole's error against its target, in the wall's plane: horizontal, vertical [m].
struct HoleError {
  double horizontal{0.0};
  double vertical{0.0};
  [[nodiscard]] double norm() const { return std::hypot(horizontal, vertical); }
};

inline HoleError error_of(const msg::SimHole& hole, const Eigen::Vector3d& target,
                          const Eigen::Vector3d& normal) {
  const Eigen::Vector3d entry(hole.entry().x(), hole.entry().y(), hole.entry().z());
  Eigen::Vector3d d = entry - target;
  d -= normal * normal.dot(d);  // in the wall's plane (the mark is 1 mm in front of the face)
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(normal).normalized();
  return {d.dot(right), d.z()};
}

/// Where a world's marks ask for holes: every blob's centre, and every ArUco marker's pattern
/// laid on the marker's true pose.
struct Target {
  std::string name;
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};
  Eigen::Vector3d normal{Eigen::Vector3d::Zero()};
};

inline std::vector<Target> targets_of(const world::World& site,
                                      const drill::PatternTable& patterns) {
  std::vector<Target> out;
  for (const world::MarkTruth& m : world::mark_truth(site)) {
    if (m.type == world::Mark::Type::kBlob) {
      out.push_back({m.name, m.centre, m.normal});
      continue;
    }
    const drill::HolePattern* pattern = patterns.find(m.id);
    if (pattern == nullptr) continue;
    const Eigen::Vector3d up = m.normal.cross(m.right);
    Eigen::Isometry3d marker = Eigen::Isometry3d::Identity();
    marker.linear().col(0) = std::cos(m.angle) * m.right + std::sin(m.angle) * up;
    marker.linear().col(2) = m.normal;
    marker.linear().col(1) = m.normal.cross(marker.linear().col(0));
    marker.translation() = m.centre;
    const auto holes = drill::pattern_holes(marker, *pattern);
    for (std::size_t i = 0; i < holes.size(); ++i)
      out.push_back({m.name + " hole " + std::to_string(i + 1), holes[i].translation(), m.normal});
  }
  return out;
}

/// The hole nearest a target (none: nullptr) and its error.
inline std::pair<const msg::SimHole*, HoleError> nearest_hole(const std::vector<msg::SimHole>& holes,
                                                              const Target& target) {
  const msg::SimHole* best = nullptr;
  HoleError best_error;
  double best_norm = std::numeric_limits<double>::infinity();
  for (const msg::SimHole& h : holes) {
    const HoleError e = error_of(h, target.position, target.normal);
    if (e.norm() < best_norm) {
      best_norm = e.norm();
      best = &h;
      best_error = e;
    }
  }
  return {best, best_error};
}

/// Odometry and the simulator's truth of the base at one moment of a run, with the drill's
/// active node then.
struct TrackPoint {
  double t{0.0};                    // [s] from the mission's start
  std::array<double, 3> odometry{};  // x, y [m], yaw [rad] in the odometry frame
  std::array<double, 3> truth{};     // x, y [m], yaw [rad] in the world
  std::array<double, 3> lean{};      // the truth's z [m], roll and pitch [rad]
  std::string active;
  Eigen::Vector3d force{Eigen::Vector3d::Zero()};  // the IMU's mean specific force (zero: none)
};

/// The arm's and legs' torques over a quarter of a second of a run: each joint's largest |effort|
/// and its last position, with the drill's active node then (what held a joint near its
/// continuous torque before a safety stop on its RMS torque).
struct TorqueSample {
  double t{0.0};  // [s] from the mission's start
  std::string active;
  std::vector<double> peak;      // per MissionRun::joint_names: largest |effort| [N m]
  std::vector<double> position;  // per MissionRun::joint_names: the last position [rad]
};

/// What a mission run left: the final status (none: the service never answered), the holes the
/// simulator's wall records, the safety state at the end, every service's log and the base's
/// track.
struct MissionRun {
  std::optional<msg::DrillStatus> status;
  std::vector<msg::SimHole> holes;
  bool safety_running{false};
  /// Times the safety layer went from RUNNING to STOPPED after the mission was sent, and its
  /// causes each time.
  int safety_stops{0};
  std::vector<std::string> stop_causes;
  std::string logs;
  std::vector<TrackPoint> track;  // every half second or so while the mission ran
  std::vector<std::string> joint_names;
  std::vector<TorqueSample> torques;  // every quarter second, the last 30 s of the run
};

/// `joint`'s torques over the last `seconds` of `run` (a line per quarter second).
inline std::string torque_trace(const MissionRun& run, const std::string& joint, double seconds = 15.0) {
  const auto it = std::find(run.joint_names.begin(), run.joint_names.end(), joint);
  if (it == run.joint_names.end() || run.torques.empty()) return joint + ": no torques recorded\n";
  const auto j = static_cast<std::size_t>(it - run.joint_names.begin());
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out << std::setprecision(1) << joint << "'s largest |torque| per quarter second over the last "
      << seconds << " s (N m, its position in rad, the drill's active node):\n";
  for (const TorqueSample& s : run.torques) {
    if (s.t < run.torques.back().t - seconds || j >= s.peak.size()) continue;
    out << "  " << s.t << " s: " << s.peak[j] << " N m at " << std::setprecision(3) << s.position[j]
        << std::setprecision(1) << " rad; " << s.active << "\n";
  }
  return out.str();
}

/// How odometry parted from the simulator's truth over `track`: odometry mapped into the world
/// by their first pair, the position error at the end, its largest value, and the `count`
/// largest growths between successive points with the drill's active node at each (where a
/// drilling pattern's holes go wrong on kinematics alone).
inline std::string odometry_drift(const std::vector<TrackPoint>& track, std::size_t count = 5) {
  if (track.size() < 2) return "odometry against truth: not recorded\n";
  const auto pose = [](const std::array<double, 3>& p) { return Eigen::Vector3d(p[0], p[1], p[2]); };
  const Eigen::Vector3d world_T_odom = mobile_base::compose(
      pose(track.front().truth), mobile_base::inverse(pose(track.front().odometry)));
  std::vector<Eigen::Vector3d> error;  // x, y [m], yaw [rad]: odometry's world pose minus the truth
  for (const TrackPoint& p : track) {
    const Eigen::Vector3d seen = mobile_base::compose(world_T_odom, pose(p.odometry));
    const Eigen::Vector3d truth = pose(p.truth);
    error.emplace_back(seen.x() - truth.x(), seen.y() - truth.y(),
                       std::remainder(seen.z() - truth.z(), 2.0 * M_PI));
  }
  std::vector<std::size_t> order(error.size() - 1);
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i + 1;
  const auto growth = [&](std::size_t i) { return (error[i].head<2>() - error[i - 1].head<2>()).norm(); };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return growth(a) > growth(b); });
  double largest = 0.0;
  for (const Eigen::Vector3d& e : error) largest = std::max(largest, e.head<2>().norm());
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out << std::setprecision(1) << "odometry against truth over " << track.back().t << " s: "
      << error.back().head<2>().norm() * 1e3 << " mm and " << error.back().z() * 1e3
      << " mrad off at the end, at most " << largest * 1e3 << " mm; largest growths:\n";
  // The angle between the IMU's mean specific force and its first: the base tilting, or
  // accelerating (the arm's weight alone tilts morphology A's standing base by 0.3 mrad at most).
  const auto turned = [&](std::size_t i) {
    const Eigen::Vector3d& g0 = track.front().force;
    const Eigen::Vector3d& g = track[i].force;
    if (g0.isZero() || g.isZero()) return std::nan("");
    return std::atan2(g0.cross(g).norm(), g0.dot(g));
  };
  double most_turned = 0.0;
  std::size_t at = 0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (turned(i) > most_turned) {
      most_turned = turned(i);
      at = i;
    }
  }
  out << "  the IMU's mean specific force turned from its first direction by at most "
      << most_turned * 1e3 << " mrad (at " << track[at].t << " s, " << track[at].active
      << "): the base tilting or accelerating\n";
  for (std::size_t k = 0; k < order.size() && k < count; ++k) {
    const std::size_t i = order[k];
    out << "  " << track[i - 1].t << "-" << track[i].t << " s: " << growth(i) * 1e3 << " mm ("
        << error[i - 1].head<2>().norm() * 1e3 << " -> " << error[i].head<2>().norm() * 1e3
        << " mm, yaw " << error[i - 1].z() * 1e3 << " -> " << error[i].z() * 1e3 << " mrad, IMU force turned "
        << turned(i - 1) * 1e3 << " -> " << turned(i) * 1e3 << " mrad; base z " << track[i - 1].lean[0] * 1e3
        << " -> " << track[i].lean[0] * 1e3 << " mm, roll " << track[i - 1].lean[1] * 1e3 << " -> "
        << track[i].lean[1] * 1e3 << " mrad, pitch " << track[i - 1].lean[2] * 1e3 << " -> "
        << track[i].lean[2] * 1e3 << " mrad; " << track[i].active << ")\n";
  }
  return out.str();
}

/// A mission in a building (paper scenario 2): the nav service maps the IFC storey and
/// localises the robot, which starts at `start` (x, y, theta in the map frame); the site is the
/// storey's world (bim::storey_world) with two blue blobs drawn 5 cm either side of the area the
/// user picks on the model (wall, at = [s, h], face), as in the paper (6.1: the dots are drawn,
/// then the area is aligned with them on the BIM).
struct Building {
  std::string ifc;
  std::string storey;
  std::array<double, 3> start{0, 0, 0};
  std::string wall;  // IFC GlobalId
  std::array<double, 2> at{0, 0};
  std::string face{"auto"};
};

/// The paper's scenario 2 in the KIT FZK house (../shared/data/bim): the ground floor; the area
/// on the living room's face (right) of the interior wall north of it (Wand-Int-ERDG-5), 1.75 m
/// along its axis, 1.2 m high; the robot starts inside the terrace door east of the spiral
/// stair, facing north, 4.3 m from where it drills, and drives around the stair.
inline Building fzk_living_room() {
  return {std::string(CONCERT_SHARED_DATA) + "/bim/AC20-FZK-Haus.ifc",
          "Erdgeschoss",
          {6.0, 1.2, M_PI / 2},
          "1$wmdwWPjDYuku_ghVkynE",
          {1.75, 1.2},
          "right"};
}

/// The mission drilling both blobs of a Building's area.
inline std::string bim_mission(const std::string& name, const Building& b = fzk_living_room()) {
  std::ostringstream m;
  m << "name: " << name << "\ndepth: 0.03\nifc: " << b.ifc << "\nstorey: " << b.storey
    << "\nareas:\n  - {name: bim, marks: blobs, wall: \"" << b.wall << "\", at: [" << b.at[0]
    << ", " << b.at[1] << "], face: " << b.face << ", expected: 2}\n";
  return m.str();
}

/// The Building's world file (a temp file): the storey's boxes and the two blobs, drawn on the
/// face the drill service's wall goal picks (its standoff 1.05 m and robot radius 0.55 m:
/// services/drill/src/dds/drill_node.cpp kWallStandoff, kRobotRadius).
inline std::string building_site(const Building& b) {
  const bim::BimModel house = bim::load_ifc(b.ifc);
  const bim::Storey& storey = house.storey(b.storey);
  world::World w = bim::storey_world(house, storey);
  bim::GoalOptions options;
  options.face = bim::face_choice(b.face);
  const bim::WallGoal goal = bim::wall_goal(house, bim::storey_map(house, storey), b.wall, b.at[0],
                                            b.at[1], 1.05, 0.55, options);
  const Eigen::Vector3d centre = goal.area_frame.translation();
  const Eigen::Vector3d normal = goal.area_frame.linear().col(2);
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(normal).normalized();
  w.marks.push_back(bim::mark_on_wall(w, b.wall, centre - 0.05 * right, normal, "bim_left", 0.025));
  w.marks.push_back(bim::mark_on_wall(w, b.wall, centre + 0.05 * right, normal, "bim_right", 0.025));
  std::printf("building: area (%.3f, %.3f, %.3f) normal (%.2f, %.2f, %.2f), base goal (%.2f, "
              "%.2f, %.2f), start (%.2f, %.2f, %.2f): %.2f m to drive\n",
              centre.x(), centre.y(), centre.z(), normal.x(), normal.y(), normal.z(),
              goal.base_pose.x(), goal.base_pose.y(), goal.base_pose.z(), b.start[0], b.start[1],
              b.start[2], std::hypot(goal.base_pose.x() - b.start[0], goal.base_pose.y() - b.start[1]));
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("drill_building_site_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(file) << bim::world_yaml(w);
  return file.string();
}

/// A service's binary: the one built beside this test, or with CONCERT_STACK_DIR set, the one of
/// that name there (a copy of the stack taken before a long benchmark, so that building on
/// while it runs does not change the services under it halfway).
inline std::string stack_binary(const std::string& built) {
  const char* dir = std::getenv("CONCERT_STACK_DIR");
  if (dir == nullptr || *dir == '\0') return built;
  return (std::filesystem::path(dir) / std::filesystem::path(built).filename()).string();
}

/// Runs `mission` (a mission file's text) with the robot of `assembly` in the world `site`, and
/// waits for its end (bounded by `timeout`) and for the holes the status counts. With a
/// `building`, the nav service runs too (started only when NAV_BINARY is defined). `map`: what
/// the planner's map is built from (concert_planner --map: world, sensors or both).
inline MissionRun run_mission(const std::string& assembly, const std::string& site,
                              const std::string& mission, std::chrono::seconds timeout,
                              const std::optional<Building>& building = std::nullopt,
                              const std::string& map = "world") {
  using namespace std::chrono_literals;
  MissionRun run;
  std::vector<std::string> robot_args = {ROBOT_BINARY, "--assembly", assembly, "--world", site};
  std::vector<std::string> nav_args;
  if (building) {
    const std::filesystem::path params = std::filesystem::temp_directory_path() /
                                         ("drill_runner_robot_" + std::to_string(::getpid()) + ".yaml");
    std::ofstream(params) << std::setprecision(17) << "sim:\n  base_position: ["
                          << building->start[0] << ", " << building->start[1]
                          << ", 0.0]\n  base_yaw: " << building->start[2] << "\n";
    robot_args.insert(robot_args.end(), {"--params", params.string()});
#ifdef NAV_BINARY
    std::ostringstream x, y, yaw;
    x << std::setprecision(17) << building->start[0];
    y << std::setprecision(17) << building->start[1];
    yaw << std::setprecision(17) << building->start[2];
    nav_args = {NAV_BINARY, "--ifc", building->ifc, "--storey", building->storey,
                "--initial-pose", x.str(), y.str(), yaw.str()};
#endif
  }
  robot_args.front() = stack_binary(ROBOT_BINARY);
  if (!nav_args.empty()) nav_args.front() = stack_binary(nav_args.front());
  testing::Process safety(dies_with_test({stack_binary(SAFETY_BINARY)}));
  testing::Process discovery(dies_with_test({stack_binary(DISCOVERY_BINARY)}));
  testing::Process modelgen(dies_with_test({stack_binary(MODELGEN_BINARY)}));
  testing::Process robot(dies_with_test(robot_args));
  testing::Process planner(dies_with_test({stack_binary(PLANNER_BINARY), "--map", map}));
  // CONCERT_TEST_UNSEEN_FRAMES=DIR keeps the drill camera's views in which a mark was looked
  // for and not found (concert_drill --unseen-frames).
  std::vector<std::string> drill_args{stack_binary(DRILL_BINARY)};
  if (const char* dir = std::getenv("CONCERT_TEST_UNSEEN_FRAMES"); dir != nullptr && *dir != '\0')
    drill_args.insert(drill_args.end(), {"--unseen-frames", dir});
  testing::Process drill(dies_with_test(drill_args));
  std::optional<testing::Process> nav;
  if (!nav_args.empty()) nav.emplace(dies_with_test(nav_args));
  const auto logs = [&] {
    return "\n--- drill:\n" + drill.err() + "--- planner:\n" + planner.err() +
           (nav ? "--- nav:\n" + nav->err() : std::string()) + "--- safety:\n" + safety.err() +
           "--- robot:\n" + robot.err() + "--- modelgen:\n" + modelgen.err();
  };
  concert::dds::Participant p({.name = "drill_mission_runner"});
  concert::dds::Reader<msg::SimHoles> holes(p, concert::dds::topics::sim_holes);
  // The safety layer's stops after the mission was sent (its latest mode, its stops' causes).
  std::mutex safety_mutex;
  bool mission_sent = false;
  std::optional<msg::SafetyMode> last_mode;
  std::vector<std::string> stop_causes;
  concert::dds::Reader<msg::SafetyState> safety_states(
      p, concert::dds::topics::safety_state, [&](const msg::SafetyState& st, const auto&) {
        std::lock_guard lock(safety_mutex);
        if (mission_sent && last_mode == msg::SAFETY_RUNNING && st.mode() == msg::SAFETY_STOPPED) {
          std::string causes;
          for (const std::string& c : st.causes()) causes += (causes.empty() ? "" : "; ") + c;
          stop_causes.push_back(causes);
        }
        last_mode = st.mode();
      });
  concert::dds::Reader<msg::DrillStatus> statuses(p, concert::dds::topics::drill_status);
  concert::dds::Writer<msg::DrillMission> missions(p, concert::dds::topics::drill_mission);
  // The base as odometry and as the simulator have it, the latest of each (a stream).
  std::mutex base_mutex;
  std::optional<msg::Odometry> odometry;
  std::deque<msg::SimTruth> truths_kept;  // the last ones: paired with odometry by stamp
  std::deque<Eigen::Vector3d> forces;     // the IMU's last specific forces
  std::string imu_name;
  // The joints' largest |effort| since the last torque sample, and their last positions.
  std::vector<double> peaks, positions;
  std::vector<std::string> joint_names;
  concert::dds::Reader<msg::JointState> joint_states(
      p, concert::dds::topics::joint_state, [&](const msg::JointState& js, const auto&) {
        std::lock_guard lock(base_mutex);
        if (joint_names.empty()) joint_names = js.name();
        if (js.name() != joint_names || js.effort().size() != js.name().size() ||
            js.position().size() != js.name().size())
          return;  // another model's joints
        peaks.resize(js.name().size(), 0.0);
        positions.resize(js.name().size(), 0.0);
        for (std::size_t i = 0; i < js.name().size(); ++i) {
          peaks[i] = std::max(peaks[i], std::abs(js.effort()[i]));
          positions[i] = js.position()[i];
        }
      });
  concert::dds::Reader<msg::Odometry> odometries(p, concert::dds::topics::odometry,
                                                 [&](const msg::Odometry& o, const auto&) {
                                                   std::lock_guard lock(base_mutex);
                                                   odometry = o;
                                                 });
  concert::dds::Reader<msg::SimTruth> truths(p, concert::dds::topics::sim_truth,
                                             [&](const msg::SimTruth& t, const auto&) {
                                               std::lock_guard lock(base_mutex);
                                               truths_kept.push_back(t);
                                               if (truths_kept.size() > 500) truths_kept.pop_front();
                                             });
  concert::dds::Reader<msg::Imu> imus(p, concert::dds::topics::imu, [&](const msg::Imu& m, const auto&) {
    std::lock_guard lock(base_mutex);
    if (imu_name.empty()) imu_name = m.sensor();
    if (m.sensor() != imu_name) return;  // one IMU's axes
    const auto& a = m.linear_acceleration();
    forces.emplace_back(a.x(), a.y(), a.z());
    if (forces.size() > 50) forces.pop_front();
  });
  if (!wait_for_err(drill, "drill: model version 1: drill", 120s) ||
      !wait_for_err(planner, "planner: model version 1", 60s) || !missions.wait_for_readers(1, 10s)) {
    run.logs = logs();
    return run;
  }
  if (nav) {  // the building's map loaded and the robot localised in it at its start
    concert::dds::Reader<msg::NavLocalisation> localisations(p, concert::dds::topics::nav_localisation);
    bool tracking = false;
    if (wait_for_err(*nav, "nav: model version 1:", 90s)) {
      for (const auto until = std::chrono::steady_clock::now() + 30s;
           !tracking && std::chrono::steady_clock::now() < until;) {
        const auto l = localisations.wait(200ms);
        tracking = l && l->state() == msg::LOCALISATION_TRACKING;
      }
    }
    if (!tracking) {
      run.logs = "nav: not localised at the start" + logs();
      return run;
    }
  }
  msg::DrillMission m;
  m.mission_id(static_cast<uint32_t>(now_ns() & 0x7fffffff));
  m.stamp_ns(now_ns());
  m.source("drill_mission_runner");
  m.name("runner");
  m.yaml(mission);
  m.base_dir(std::filesystem::temp_directory_path().string());
  {
    std::lock_guard lock(safety_mutex);
    mission_sent = true;
  }
  missions.write(m);
  const auto mean_force = [&] {  // under base_mutex
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& f : forces) sum += f;
    return forces.empty() ? sum : Eigen::Vector3d(sum / static_cast<double>(forces.size()));
  };
  const auto started = std::chrono::steady_clock::now();
  auto recorded = started - 1s;
  auto torque_recorded = started;
  std::string active;
  for (const auto until = started + timeout; std::chrono::steady_clock::now() < until;) {
    const auto s = statuses.wait(250ms);
    if (s && s->mission_id() == m.mission_id()) active = s->active();
    const auto now = std::chrono::steady_clock::now();
    if (now - torque_recorded >= 250ms) {
      torque_recorded = now;
      std::lock_guard lock(base_mutex);
      if (!peaks.empty()) {
        if (run.joint_names.empty()) run.joint_names = joint_names;
        run.torques.push_back({std::chrono::duration<double>(now - started).count(), active, peaks, positions});
        if (run.torques.size() > 120) run.torques.erase(run.torques.begin());
        std::fill(peaks.begin(), peaks.end(), 0.0);
      }
    }
    if (now - recorded >= 500ms) {
      recorded = now;
      std::lock_guard lock(base_mutex);
      // Both stamped in the simulator's time: the truth nearest the odometry's moment.
      const msg::SimTruth* truth = nullptr;
      for (const msg::SimTruth& t : truths_kept) {
        if (odometry && (truth == nullptr || std::llabs(t.stamp_ns() - odometry->stamp_ns()) <
                                                 std::llabs(truth->stamp_ns() - odometry->stamp_ns())))
          truth = &t;
      }
      if (odometry && truth && std::llabs(truth->stamp_ns() - odometry->stamp_ns()) < 50'000'000)
        run.track.push_back({std::chrono::duration<double>(now - started).count(),
                             {odometry->x(), odometry->y(), odometry->yaw()},
                             {truth->x(), truth->y(), truth->yaw()},
                             {truth->z(), truth->roll(), truth->pitch()},
                             active,
                             mean_force()});
    }
    if (!s || s->mission_id() != m.mission_id()) continue;
    run.status = s;
    if (s->state() != msg::DRILL_RUNNING && s->state() != msg::DRILL_IDLE) break;
  }
  std::optional<msg::SimHoles> cut;
  const std::size_t drilled = run.status ? run.status->holes_drilled() : 0;
  for (const auto until = std::chrono::steady_clock::now() + 10s;
       std::chrono::steady_clock::now() < until;) {
    if (auto h = holes.wait(200ms)) cut = h;
    if (cut && cut->holes().size() >= drilled) break;
  }
  if (cut) run.holes = cut->holes();
  {
    std::lock_guard lock(safety_mutex);
    run.safety_running = last_mode == msg::SAFETY_RUNNING;
    run.safety_stops = static_cast<int>(stop_causes.size());
    run.stop_causes = stop_causes;
  }
  run.logs = logs();
  return run;
}

/// A mission state as the CLI prints it.
inline const char* state_name(msg::DrillMissionState state) {
  constexpr const char* kNames[] = {"idle", "running", "succeeded", "failed", "aborted"};
  const auto i = static_cast<std::size_t>(state);
  return i < std::size(kNames) ? kNames[i] : "unknown";
}

}  // namespace concert::system_test
