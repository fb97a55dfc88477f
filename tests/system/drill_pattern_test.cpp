// An ArUco pattern drilled end to end in simulation (paper section 5.4, scenario 3): morphology
// A (the paper's) in front of the benchmark's pattern wall (deploy/bench/drill_patterns_site.yaml),
// the row at 1.5 m: marker 0 at 1.65 m selects pattern 0 (services/drill/config/patterns.yaml: a
// 60 cm row of 4 holes 0.2 m apart, 0.15 m below the marker). Every service of the drilling stack
// on one machine over loopback DDS, the cameras with their noise. The area is located from a
// point picked near the marker; the drill service plans and executes the approach, finds the
// marker and its pattern, places the base once for the row (a whole-body posture from which the
// arm alone reaches every hole and the camera the marker: services/drill, "Placing the base"),
// measures the pattern again from there, and drills the holes by the kinematics alone (no visual
// servoing, as in the paper) with the base standing.
// Judged against the simulator's truth: the holes its wall records (concert/sim/holes) against
// the pattern laid on the marker's true pose (libs/world), not against the service's report.
// The paper's aim for patterns: median error <= 3 mm (services/drill/README.md, figures).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "drill_test_report.hpp"

namespace concert::system_test {
namespace {

using namespace std::chrono_literals;

const std::string kAssembly =
    std::string(CONCERT_SOURCE_DIR) + "/services/planner/data/morphology_a.yaml";
const std::string kSite = std::string(CONCERT_SOURCE_DIR) + "/deploy/bench/drill_patterns_site.yaml";

TEST(DrillPattern, DrillsTheRowOfAnArucoMarkerByTheKinematicsAlone) {
  const MissionRun run = run_mission(kAssembly, kSite,
                                     "name: system pattern\n"
                                     "depth: 0.03\n"
                                     "areas:\n"
                                     "  - {name: row_150, marks: aruco, point: [2.2, -0.3, 1.65]}\n",
                                     900s);
  std::ostringstream summary;
  [&] {
    ASSERT_TRUE(run.status) << "no status from the drill service";
    summary << "drill: " << state_name(run.status->state()) << " (" << run.status->reason()
            << "), " << run.status->holes_drilled() << " of " << run.status->holes_marked()
            << " holes; the simulator recorded " << run.holes.size() << "\n";
    EXPECT_EQ(run.status->state(), msg::DRILL_SUCCEEDED) << run.status->reason();
    EXPECT_EQ(run.status->holes_drilled(), 4u);
    EXPECT_EQ(run.status->holes_marked(), 4u);
    const drill::PatternTable patterns = drill::load_patterns(
        std::string(CONCERT_SOURCE_DIR) + "/services/drill/config/patterns.yaml");
    std::vector<double> errors;
    for (const Target& t : targets_of(world::load_world_file(kSite), patterns)) {
      if (t.name.rfind("row_150", 0) != 0) continue;  // the wall's other rows: the benchmark's
      const auto [hole, e] = nearest_hole(run.holes, t);
      // A hole within 5 cm is this mark's (the next mark is 0.2 m away).
      if (hole == nullptr || e.norm() > 0.05) {
        ADD_FAILURE() << "no hole for " << t.name;
        summary << "no hole within 5 cm of " << t.name << "\n";
        continue;
      }
      std::ostringstream line;
      line << "hole for " << t.name << ": x " << e.horizontal * 1e3 << " mm, y "
           << e.vertical * 1e3 << " mm, depth " << hole->depth() * 1e3 << " mm";
      std::cout << line.str() << std::endl;
      summary << line.str() << "\n";
      EXPECT_GT(hole->depth(), 0.022) << t.name;  // measured 27-29 mm of the 30 asked
      // No hole where odometry alone put it: that drifts 5-35 mm over a whole-body move.
      EXPECT_LT(e.norm(), 0.01) << t.name;
      errors.push_back(e.norm());
    }
    ASSERT_EQ(errors.size(), 4u);
    std::sort(errors.begin(), errors.end());
    const double median = 0.5 * (errors[1] + errors[2]);
    EXPECT_LE(median, 0.003);  // the paper's aim for patterns
  }();
  // The end state: the robot never stopped by the safety layer.
  expect_safety_and_report(run, summary);
}

}  // namespace
}  // namespace concert::system_test
