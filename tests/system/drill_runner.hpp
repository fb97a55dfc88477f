#pragma once
// A drilling mission on a whole simulated stack, judged against the simulator's truth: shared by
// the drilling system test and its benchmark (bench_drill_mission). Every service is a process
// (safety, discovery, modelgen, the robot with MuJoCo and the cameras' noise, planner, drill);
// the holes are the ones the simulator's wall records (concert/sim/holes), the targets the marks'
// true positions (libs/world) and the patterns laid on the markers' true poses.

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
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

/// What a mission run left: the final status (none: the service never answered), the holes the
/// simulator's wall records, the safety state at the end, and every service's log.
struct MissionRun {
  std::optional<msg::DrillStatus> status;
  std::vector<msg::SimHole> holes;
  bool safety_running{false};
  std::string logs;
};

/// Runs `mission` (a mission file's text) with the robot of `assembly` in the world `site`, and
/// waits for its end (bounded by `timeout`) and for the holes the status counts.
inline MissionRun run_mission(const std::string& assembly, const std::string& site,
                              const std::string& mission, std::chrono::seconds timeout) {
  using namespace std::chrono_literals;
  MissionRun run;
  testing::Process safety(dies_with_test({SAFETY_BINARY}));
  testing::Process discovery(dies_with_test({DISCOVERY_BINARY}));
  testing::Process modelgen(dies_with_test({MODELGEN_BINARY}));
  testing::Process robot(dies_with_test({ROBOT_BINARY, "--assembly", assembly, "--world", site}));
  testing::Process planner(dies_with_test({PLANNER_BINARY}));
  testing::Process drill(dies_with_test({DRILL_BINARY}));
  const auto logs = [&] {
    return "\n--- drill:\n" + drill.err() + "--- planner:\n" + planner.err() + "--- safety:\n" +
           safety.err() + "--- robot:\n" + robot.err() + "--- modelgen:\n" + modelgen.err();
  };
  concert::dds::Participant p({.name = "drill_mission_runner"});
  concert::dds::Reader<msg::SimHoles> holes(p, concert::dds::topics::sim_holes);
  concert::dds::Reader<msg::SafetyState> safety_states(p, concert::dds::topics::safety_state);
  concert::dds::Reader<msg::DrillStatus> statuses(p, concert::dds::topics::drill_status);
  concert::dds::Writer<msg::DrillMission> missions(p, concert::dds::topics::drill_mission);
  if (!wait_for_err(drill, "drill: model version 1: drill", 120s) ||
      !wait_for_err(planner, "planner: model version 1", 60s) || !missions.wait_for_readers(1, 10s)) {
    run.logs = logs();
    return run;
  }
  msg::DrillMission m;
  m.mission_id(static_cast<uint32_t>(now_ns() & 0x7fffffff));
  m.stamp_ns(now_ns());
  m.source("drill_mission_runner");
  m.name("runner");
  m.yaml(mission);
  m.base_dir(std::filesystem::temp_directory_path().string());
  missions.write(m);
  for (const auto until = std::chrono::steady_clock::now() + timeout;
       std::chrono::steady_clock::now() < until;) {
    const auto s = statuses.wait(500ms);
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
  const auto state = safety_states.wait(5s);
  run.safety_running = state && state->mode() == msg::SAFETY_RUNNING;
  run.logs = logs();
  return run;
}

}  // namespace concert::system_test
