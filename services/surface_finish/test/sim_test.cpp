// A spray run in the MuJoCo simulator (libs/sim): the paper's spraying robot (morphology B with
// the Spraying Tool, deploy/demo/spraying_robot.yaml) covers a short area of the wall; the
// deposition model is fed the simulator's true TCP pose every millisecond. Aims (issue 19):
// every coat 100 mm +- 5 mm wide, |delta h| <= 5 mm between adjacent strokes' lower ends,
// coverage >= 99 % of the rectangle.
#include <gtest/gtest.h>

#include <cstdio>

#include "finish_fixture.hpp"
#include "surface_finish/sim_run.hpp"

namespace concert::surface_finish {
namespace {

TEST(SpraySim, ShortAreaMeetsCoatWidthDeltaHAndCoverage) {
  SprayRunParams p;
  p.assembly = test::source_dir() / "deploy/demo/spraying_robot.yaml";
  p.module_dbs = {test::project_db()};
  // A short area: 0.4 m x 0.4 m in the band (x [-0.7, 0.7] m, heights [2.05, 2.5] m at 1.4 m
  // from the wall: see the README on continuous torques).
  p.rects = {Rect{-0.6, -0.2, 2.05, 2.45}};
  const SprayRunResult r = run_spray_in_sim(p);
  ASSERT_EQ(r.reports.size(), 1u);
  const SprayReport& rep = r.reports.front();
  std::printf("%s\n", SprayDeposition::to_json(rep).c_str());
  std::printf("max TCP error %.1f mm, standoff error %.1f mm, %.1f s simulated in %.1f s\n", r.max_tcp_error * 1e3,
              r.max_standoff_error * 1e3, r.sim_time, r.wall_time);
  ASSERT_EQ(rep.coats.size(), r.plans.front().strokes.size());
  EXPECT_EQ(rep.coats.size(), 5u);  // 0.4 m with 0.1 m coats overlapping 10 %
  for (const CoatMeasure& c : rep.coats) {
    EXPECT_NEAR(c.width_min, 0.1, 0.005) << c.x;
    EXPECT_NEAR(c.width_max, 0.1, 0.005) << c.x;
  }
  EXPECT_LE(rep.max_abs_delta_h, 0.005);
  EXPECT_GE(rep.coverage, 0.99);
  EXPECT_GT(r.max_tcp_error, 0.0);  // the simulator's TCP, not the plan's
}

}  // namespace
}  // namespace concert::surface_finish

namespace concert::surface_finish {
namespace {

// A sanding run in MuJoCo (issue 19): the sanding robot (deploy/demo/sanding_robot.yaml) on the
// bumpy plaster of deploy/demo/sand_site.yaml (3 mm bumps, 4 mm holes), its centre area, 30 N,
// the admittance law closed on the force estimated from the joint torques, judged on the
// simulator's contact force (averaged over 100 ms: SandRunParams::truth_window), the disc
// running (SandRunParams::disc_rpm). The aim: the true force within +-3 N for >= 95 %
// of the stroke time. Measured 99.6 % (the run is deterministic; 99.5-99.9 % with the disc at
// 600-1800 rpm or the law every 10 ms); asserted >= 97 %, the paper's +-10 N band too.
TEST(SandSim, CentreAreaHoldsThirtyNewtonsOnTheBumpyWall) {
  SandRunParams p;
  p.assembly = test::source_dir() / "deploy/demo/sanding_robot.yaml";
  p.module_dbs = {test::project_db()};
  p.world = test::source_dir() / "deploy/demo/sand_site.yaml";
  const SandRunResult r = run_sand_in_sim(p);
  std::printf("%s\n", sand_report_json(r, p).c_str());
  std::printf("%.1f s simulated in %.1f s\n", r.sim_time, r.wall_time);
  EXPECT_TRUE(r.aborted.empty()) << r.aborted;
  EXPECT_EQ(r.plan.strokes.size(), 3u);  // 0.45 m wide with the 0.23 m disc, 10 % overlap
  EXPECT_GT(r.truth.duration, 3.0);
  EXPECT_LT(r.disc_friction, 0.02);  // 0.8 x 0.1 m/s / (1000 rpm x 0.115 m)
  // The law holds what the robot measures.
  EXPECT_NEAR(r.estimated.mean, 30.0, 0.5);
  EXPECT_GE(r.estimated.within_fraction, 0.97);
  // The wall feels it: mean within 1 N, the paper's +-10 N band, the issue's +-3 N for >= 95 %.
  EXPECT_NEAR(r.truth.mean, 30.0, 1.0);
  EXPECT_GE(r.truth_within_10, 0.999);
  EXPECT_GE(r.truth.within_fraction, 0.97);
  EXPECT_LT(r.max_truth_error, 6.0);
  EXPECT_LT(r.mean_abs_truth_error, 1.2);
  EXPECT_LT(r.estimated.estimate_error_rms, 1.5);
  // The truth is the simulator's, not the estimate: they differ.
  EXPECT_GT(r.estimated.estimate_error_rms, 0.1);
  // In contact all along and the TCP on its stroke.
  EXPECT_GT(r.contact_step_fraction, 0.85);
  EXPECT_LT(r.max_lateral_error, 0.015);
}

// The cause of the earlier 85 %: a standing disc (a dry sanding block, friction 0.8 on
// the plaster) sticks and slips along the stroke (the TCP lags 2 cm, then jumps at 0.17 m/s),
// and the jolts shake the contact force by +-8 N (100 ms average) where the estimate from the
// joint torques, a quasi-static one, sees less than half of it.
TEST(SandSim, StandingDiscSticksAndSlips) {
  SandRunParams p;
  p.assembly = test::source_dir() / "deploy/demo/sanding_robot.yaml";
  p.module_dbs = {test::project_db()};
  p.world = test::source_dir() / "deploy/demo/sand_site.yaml";
  p.disc_rpm = 0.0;
  const SandRunResult r = run_sand_in_sim(p);
  std::printf("standing disc: truth within +-3 N %.1f %%, max lateral error %.1f mm, estimate - truth RMS %.2f N\n",
              100.0 * r.truth.within_fraction, r.max_lateral_error * 1e3, r.estimated.estimate_error_rms);
  EXPECT_TRUE(r.aborted.empty()) << r.aborted;
  EXPECT_NEAR(r.disc_friction, 0.8, 1e-12);
  EXPECT_LT(r.truth.within_fraction, 0.92);
  EXPECT_GT(r.max_lateral_error, 0.015);
  EXPECT_GT(r.estimated.estimate_error_rms, 1.5);
}

// Without the law (the reference left at the nominal surface, a 1 N/m-s gain that cannot move
// it), the same run does not hold the setpoint: the test above can fail.
TEST(SandSim, WithoutTheLawTheForceIsNotHeld) {
  SandRunParams p;
  p.assembly = test::source_dir() / "deploy/demo/sanding_robot.yaml";
  p.module_dbs = {test::project_db()};
  p.world = test::source_dir() / "deploy/demo/sand_site.yaml";
  p.admittance.kp = 1e-9;
  p.admittance.kd = 0.0;
  const SandRunResult r = run_sand_in_sim(p);
  std::printf("without the law: truth mean %.2f N, within +-3 N %.1f %%\n", r.truth.mean, 100.0 * r.truth.within_fraction);
  EXPECT_LT(r.truth.within_fraction, 0.5);
}

}  // namespace
}  // namespace concert::surface_finish
