// Benchmark (not a test): the follow-me MPC's solve time along a pull past obstacles (warm-
// started, Ipopt), with the follow lag, the peak interaction force and the minimum clearance.
//   bench_collab_mpc [seconds]
#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "../test/example_arm.hpp"

int main(int argc, char** argv) {
  using namespace concert::collab;
  const double seconds = argc > 1 ? std::atof(argv[1]) : 20.0;
  const auto spheres = perimeter_spheres(1.0, 0.7);
  FollowMeMpc mpc(MpcParams{}, test::ExampleArm::limits(), spheres);
  const std::vector<test::Pillar> route{{Eigen::Vector2d(3.0, 1.1), 0.3}, {Eigen::Vector2d(6.0, -1.0), 0.4},
                                        {Eigen::Vector2d(9.0, 0.0), 0.3}};
  const auto run = test::pull(mpc, spheres, route, seconds);
  auto ms = run.solve_ms;
  std::sort(ms.begin(), ms.end());
  auto pct = [&](double p) { return ms.empty() ? 0.0 : ms[std::min(ms.size() - 1, static_cast<std::size_t>(p * static_cast<double>(ms.size())))]; };
  auto cpu = run.solve_cpu_ms;
  std::sort(cpu.begin(), cpu.end());
  auto cpct = [&](double p) { return cpu.empty() ? 0.0 : cpu[std::min(cpu.size() - 1, static_cast<std::size_t>(p * static_cast<double>(cpu.size())))]; };
  auto it = run.iterations;
  std::sort(it.begin(), it.end());
  std::printf("solves %zu (warm %d, failed %d)\n", ms.size(), run.warm, run.failures);
  std::printf("solve time ms: median %.2f  p90 %.2f  p99 %.2f  max %.2f\n", pct(0.5), pct(0.9), pct(0.99),
              ms.empty() ? 0.0 : ms.back());
  std::printf("solve CPU time ms (the thread's): median %.2f  p90 %.2f  p99 %.2f\n", cpct(0.5), cpct(0.9), cpct(0.99));
  std::printf("iterations: median %d  max %d\n", it.empty() ? 0 : it[it.size() / 2], it.empty() ? 0 : it.back());
  std::printf("base travel %.2f m, mean follow lag %.3f m, peak force %.1f N, min clearance %.3f m\n",
              run.base_travel, run.mean_lag, run.peak_force, run.min_clearance);
  return run.failures == 0 ? 0 : 1;
}
