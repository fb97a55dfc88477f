// The collaborative transport (issue #18) in the simulator, end to end (collab_transport.hpp):
// teaching -> close -> lift -> follow me along a route past a pillar and a crate -> place ->
// teaching -> open, on the paper's transport robot in MuJoCo with a simulated person pulling the
// gripper; judged against the simulator's truth.
#include "collab_transport.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

namespace concert::system_test::transport {
namespace {

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += "\n  " + x;
  return s;
}

void print(const Result& r) {
  auto ms = r.solve_ms;
  std::sort(ms.begin(), ms.end());
  std::printf("states:%s\n", joined(r.states).c_str());
  std::printf(
      "guided %.3f m, lifted %.3f m, placed %.3f m, jaw closed %.2f final %.2f (open %.2f)\n",
      r.guided, r.lifted, r.placed, r.jaw_closed, r.jaw_final, r.jaw_open);
  std::printf("follow %.1f s over a %.2f m route, base travel %.2f m, end error %.3f m\n",
              r.follow_time, r.route_length, r.base_travel, r.end_error);
  std::printf("lag mean %.3f max %.3f m; pull peak %.1f N (estimated %.1f N), mean %.1f N\n",
              r.mean_lag, r.max_lag, r.peak_force, r.peak_force_estimated, r.mean_force);
  std::printf("clearance: footprint %.3f m, MPC spheres %.3f m; peak contact on base/arm %.1f N\n",
              r.min_clearance, r.min_sphere_clearance, r.peak_contact);
  if (!ms.empty())
    std::printf("MPC: %zu solves, %d failed, median %.1f ms, p99 %.1f ms; run %.1f s wall\n",
                ms.size(), r.failures, ms[ms.size() / 2],
                ms[std::min(ms.size() - 1, ms.size() * 99 / 100)], r.wall_seconds);
}

TEST(CollabTransport, TheWholeTaskWithAPersonPullingPastObstacles) {
  const Result r = run(CONCERT_SOURCE_DIR);
  print(r);
  // The state sequence of the task (Fig. 13's first half), each command accepted.
  const std::vector<std::string> expected{
      "stop",      "teaching/general", "teaching/close",   "autonomous/lift",
      "follow-me", "autonomous/place", "teaching/general", "teaching/open"};
  EXPECT_EQ(r.states, expected) << joined(r.log);
  // Open was said twice where it would drop the object (autonomous, follow-me): ignored both times.
  ASSERT_EQ(r.ignored.size(), 2u) << joined(r.log);
  for (const auto& i : r.ignored) EXPECT_EQ(i.rfind("open: ", 0), 0u) << i;

  // Teaching: the gravity-compensated arm went where the hand guided it (0.14 m).
  EXPECT_GT(r.guided, 0.08);
  // The gripper closed, then opened at the end.
  EXPECT_NEAR(r.jaw_closed, r.jaw_shut, 0.1);
  EXPECT_NEAR(r.jaw_final, r.jaw_open, 0.1);
  // Lift and place moved the object up and down by the lift height (0.15 m).
  EXPECT_NEAR(r.lifted, 0.15, 0.04);
  EXPECT_NEAR(r.placed, 0.15, 0.04);

  // Follow-me: the robot carried it to the route's end (8.9 m) behind the person.
  EXPECT_LT(r.end_error, 0.15);
  EXPECT_GT(r.base_travel, 0.8 * r.route_length);
  EXPECT_LT(r.follow_time, 40.0);
  EXPECT_LT(r.mean_lag, 0.25);  // the README's bound (measured about 0.14 m)
  // The person never had to pull hard (the README's bound; measured 33-35 N).
  EXPECT_LT(r.peak_force, 60.0);
  EXPECT_GT(r.peak_force_estimated, 5.0);  // the robot felt the pull (from its joint torques)
  // Clear of the pillar and the crate: the footprint kept the README's 8 cm (measured about
  // 0.12 m), nothing hit the base or the arm, and the MPC's own spheres kept a margin (0.05 m;
  // the grid's cells add up to 0.07 m on top, the soft constraint gives some back).
  EXPECT_GT(r.min_clearance, 0.08);
  EXPECT_GT(r.min_sphere_clearance, 0.0);
  EXPECT_LT(r.peak_contact, 1.0);
  EXPECT_LE(r.failures, static_cast<int>(r.solve_ms.size() / 50));
}

// A heavy object (10 kg, its weight hung from the TCP in MuJoCo from lift on): collab tells the
// robot the payload in its Cartesian hold, the robot adds its weight to the gravity compensation,
// and the lift reaches its height; without the payload field the 800 N/m hold sags by about
// m g / k = 0.12 m. Two seconds of holding after the lift's 2.5 s.
TEST(CollabTransport, AHeavyObjectIsLiftedToItsHeightWhenTheRobotKnowsItsMass) {
  Params p;
  p.object_mass = 10.0;
  p.stop_after_lift = 2.0;
  const Result with = run(CONCERT_SOURCE_DIR, p);
  p.send_payload = false;
  const Result without = run(CONCERT_SOURCE_DIR, p);
  std::printf("10 kg object: lift error %.4f m with the payload sent, %.4f m without\n",
              with.lift_error, without.lift_error);
  const std::vector<std::string> expected{"stop", "teaching/general", "teaching/close",
                                          "autonomous/lift"};
  EXPECT_EQ(with.states, expected);
  EXPECT_NEAR(with.lift_error, 0.0, 0.02);  // holds the lift height within 2 cm
  EXPECT_LT(without.lift_error, -0.08);     // sags
}

// The counter-test: the same pull with the obstacles unseen by the MPC runs the base into the
// pillar (the straight path leaves 0.55 m to its centre, the footprint and the pillar need 0.6 m),
// so the test above measures the avoidance, not a route that was clear anyway.
TEST(CollabTransport, UnseenObstaclesAreNotAvoided) {
  Params p;
  p.see_obstacles = false;
  p.follow_timeout = 10.0;  // past the pillar (the base's rear clears it after about 8.5 s)
  const Result r = run(CONCERT_SOURCE_DIR, p);
  print(r);
  // The footprint rectangle overlaps the pillar (measured -0.045 m). The simulated robot's
  // collision shapes are smaller than its footprint (sensors stand out and have none), so this
  // is a geometric overlap, not always a contact in MuJoCo.
  EXPECT_LT(r.min_clearance, 0.0);
  EXPECT_LT(r.min_sphere_clearance, 0.0);
}

}  // namespace
}  // namespace concert::system_test::transport
