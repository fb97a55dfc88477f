// A drilling mission end to end in simulation (paper section 5.4, scenario 1): the drill robot of
// deploy/demo/drill_robot.yaml in front of the demo's wall (deploy/demo/drill_site.yaml: two blue
// marker-pen blobs 0.1 m apart), every service on one machine over loopback DDS, the cameras with
// their noise. The area is located from a point picked on the wall; the drill service plans and
// executes the approach through the planner and the robot, detects both blobs with the drill
// camera and drills both (expected: 2), each hole's drilling posture planned, the blob measured
// again from there, drilled with Cartesian impedance and visual servoing.
// The point is picked on blob_1, 5 mm from its centre, as a user clicks the area to drill. The
// approach drifts odometry by up to some 5 cm along the wall, about half the blobs' spacing: the
// blobs the start view showed are seen again as a set after the approach and the pick moves with
// them (the log: "2 of the start view's 2 blobs seen again N mm along the wall"), and the drill
// log names the blobs it saw, nearest first, with their distances.
// The planner's map is built from the robot's own lidars and depth cameras (concert_planner --map
// sensors, paper 5.4.1), not from the simulator's description of the world.
// Judged against the simulator's truth: the holes its wall records (concert/sim/holes) against
// the blobs' true positions (libs/world); not against the service's own report. The ArUco
// pattern of the same wall is a scenario of the benchmark (bench_drill_mission --scenario demo);
// a pattern of scenario 3 is drill_pattern_test's.
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <string>

#include "drill_test_report.hpp"

namespace concert::system_test {
namespace {

using namespace std::chrono_literals;

const std::string kAssembly = std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_robot.yaml";
const std::string kSite = std::string(CONCERT_SOURCE_DIR) + "/deploy/demo/drill_site.yaml";

// The targets of the demo wall whose name starts with `prefix`, each hole's error printed; the
// errors in target order.
std::vector<HoleError> score(const MissionRun& run, const std::string& prefix) {
  const drill::PatternTable patterns =
      drill::load_patterns(std::string(CONCERT_SOURCE_DIR) + "/services/drill/config/patterns.yaml");
  std::vector<HoleError> errors;
  for (const Target& t : targets_of(world::load_world_file(kSite), patterns)) {
    if (t.name.rfind(prefix, 0) != 0) continue;
    const auto [hole, e] = nearest_hole(run.holes, t);
    if (hole == nullptr) {
      ADD_FAILURE() << "no hole for " << t.name;
      continue;
    }
    std::cout << "hole for " << t.name << ": x " << e.horizontal * 1e3 << " mm, y "
              << e.vertical * 1e3 << " mm, depth " << hole->depth() * 1e3 << " mm" << std::endl;
    EXPECT_GT(hole->depth(), 0.022) << t.name;  // measured 25-28 mm of the 30 asked (README)
    errors.push_back(e);
  }
  return errors;
}

TEST(DrillMission, DrillsTheBlobsOnTheDemoWallWithVisualServoing) {
  const MissionRun run = run_mission(kAssembly, kSite,
                                     "name: system test\n"
                                     "depth: 0.03\n"
                                     "areas:\n"
                                     "  - {name: blobs, marks: blobs, point: [2.2, 0.045, 1.2], expected: 2}\n",
                                     600s, std::nullopt, "sensors");
  std::ostringstream summary;
  [&] {
    ASSERT_TRUE(run.status) << "no status from the drill service";
    summary << "drill: " << state_name(run.status->state()) << " (" << run.status->reason()
            << "), " << run.status->holes_drilled() << " of " << run.status->holes_marked()
            << " holes\n";
    EXPECT_EQ(run.status->state(), msg::DRILL_SUCCEEDED) << run.status->reason();
    EXPECT_EQ(run.status->holes_drilled(), 2u);
    EXPECT_EQ(run.status->holes_marked(), 2u);
    // The simulator's truth: two holes, one at each blob.
    summary << "simulator: " << run.holes.size() << " hole(s)\n";
    EXPECT_EQ(run.holes.size(), 2u);
    const std::vector<HoleError> errors = score(run, "blob_");
    ASSERT_EQ(errors.size(), 2u);
    for (std::size_t i = 0; i < errors.size(); ++i) {
      summary << "hole for blob_" << i + 1 << ": " << errors[i].norm() * 1e3 << " mm off\n";
      EXPECT_LT(errors[i].norm(), 0.005) << "blob_" << i + 1;  // the paper's aim with visual servoing: max 5 mm
    }
  }();
  // The planner's map came from the robot's lidars and depth cameras (paper 5.4.1), not from
  // the simulator's description of the world.
  EXPECT_NE(run.logs.find("planner: sensor map: used lidar"), std::string::npos);
  EXPECT_NE(run.logs.find("not used: the map comes from the sensors"), std::string::npos);
  // The end state: the robot never stopped by the safety layer.
  expect_safety_and_report(run, summary);
}

}  // namespace
}  // namespace concert::system_test
