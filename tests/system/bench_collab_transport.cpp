// Benchmark (not a test): the collaborative transport on the MuJoCo robot (collab_transport.hpp):
// follow lag and interaction force along the route, minimum obstacle clearance, MPC solve time.
//   bench_collab_transport [WALK_SPEED m/s] [CONTROL_RATE Hz] [PERIOD: 1 the MPC knows the
//   control period (default), 0 one MPC step per solve as before]   (--help)
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "collab_transport.hpp"
#include "concert/cli/cli.hpp"

namespace {

int bench(const concert::system_test::transport::Params& p, const std::string& trace) {
  using namespace concert::system_test::transport;
  const Result r = run(CONCERT_SOURCE_DIR, p);
  auto ms = r.solve_ms;
  std::sort(ms.begin(), ms.end());
  auto pct = [&](double q) {
    return ms.empty() ? 0.0
                      : ms[std::min(ms.size() - 1,
                                    static_cast<std::size_t>(q * static_cast<double>(ms.size())))];
  };
  auto cpu = r.solve_cpu_ms;
  std::sort(cpu.begin(), cpu.end());
  auto cpct = [&](double q) {
    return cpu.empty()
               ? 0.0
               : cpu[std::min(cpu.size() - 1,
                              static_cast<std::size_t>(q * static_cast<double>(cpu.size())))];
  };
  auto it = r.iterations;
  std::sort(it.begin(), it.end());
  std::printf("walk %.2f m/s, collab loop %.0f Hz; states:", p.walk_speed, p.control_rate);
  for (const auto& s : r.states) std::printf(" %s", s.c_str());
  std::printf(
      "\nroute %.2f m in %.1f s of follow-me; base travel %.2f m; TCP to the route's end %.3f m\n",
      r.route_length, r.follow_time, r.base_travel, r.end_error);
  std::printf("follow lag (hand - TCP, plane): mean %.3f m, max %.3f m\n", r.mean_lag, r.max_lag);
  std::printf(
      "interaction force (the person's pull, truth): mean %.1f N, peak %.1f N; robot's estimate "
      "peak %.1f N\n",
      r.mean_force, r.peak_force, r.peak_force_estimated);
  std::printf(
      "min clearance: footprint %.3f m, MPC spheres %.3f m; peak contact on base/arm %.1f N\n",
      r.min_clearance, r.min_sphere_clearance, r.peak_contact);
  if (p.cart) std::printf("min clearance to the moving cart: %.3f m\n", r.min_cart_clearance);
  std::printf(
      "MPC solves %zu (failed %d): median %.2f ms, p90 %.2f, p99 %.2f, max %.2f; iterations median "
      "%d max %d\n",
      ms.size(), r.failures, pct(0.5), pct(0.9), pct(0.99), ms.empty() ? 0.0 : ms.back(),
      it.empty() ? 0 : it[it.size() / 2], it.empty() ? 0 : it.back());
  std::printf("MPC solve CPU time (the thread's): median %.2f ms, p90 %.2f, p99 %.2f\n", cpct(0.5),
              cpct(0.9), cpct(0.99));
  // Where the time goes: iterations against the cost of one, warm starts, how solves ended.
  std::vector<double> per_it;
  std::size_t warm = 0;
  for (std::size_t i = 0; i < r.solve_cpu_ms.size(); ++i) {
    if (r.iterations[i] > 0) per_it.push_back(r.solve_cpu_ms[i] / r.iterations[i]);
    warm += r.warm[i] ? 1 : 0;
  }
  std::sort(per_it.begin(), per_it.end());
  std::printf("CPU per iteration: median %.2f ms; warm starts %zu of %zu; iterations:", 
              per_it.empty() ? 0.0 : per_it[per_it.size() / 2], warm, r.solve_cpu_ms.size());
  std::map<int, int> hist;
  for (int i : r.iterations) ++hist[std::min(i, 20)];
  for (const auto& [i, c] : hist) std::printf(" %d%s:%d", i, i == 20 ? "+" : "", c);
  std::printf("\nsolves ended:");
  for (const auto& [s, c] : r.statuses) std::printf(" [%s] %d", s.c_str(), c);
  std::printf("\n");
  if (!trace.empty()) {
    std::FILE* f = std::fopen(trace.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "bench_collab_transport: cannot write %s\n", trace.c_str());
      return 1;
    }
    std::fprintf(f, "solve,iterations,cpu_ms,wall_ms,warm,force_estimated,force_true\n");
    for (std::size_t i = 0; i < r.solve_cpu_ms.size(); ++i)
      std::fprintf(f, "%zu,%d,%.3f,%.3f,%d,%.2f,%.2f\n", i, r.iterations[i], r.solve_cpu_ms[i],
                   r.solve_ms[i], r.warm[i] ? 1 : 0, r.force_estimated[i], r.force_true[i]);
    std::fclose(f);
  }
  std::printf("lift %.3f m, place %.3f m; wall time %.1f s\n", r.lifted, r.placed, r.wall_seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_collab_transport",
                        "The collaborative transport on the MuJoCo robot with a simulated person "
                        "(in-process, simulated time): follow lag, interaction force, obstacle "
                        "clearance, MPC solve time.",
                        std::cout, std::cerr);
  concert::system_test::transport::Params p;
  int knows_period = 1;
  std::string trace;
  cli.app()
      .add_option("WALK_SPEED", p.walk_speed, "the person's walking speed [m/s]")
      ->capture_default_str()
      ->check(concert::cli::number(0.01, 3.0));
  cli.app()
      .add_option("CONTROL_RATE", p.control_rate, "the collab loop's rate [Hz]")
      ->capture_default_str()
      ->check(concert::cli::number(1.0, 1000.0));
  cli.app()
      .add_option("PERIOD", knows_period,
                  "1: the MPC knows the control period (default); 0: one MPC step per solve, as "
                  "before the fix")
      ->capture_default_str()
      ->check(concert::cli::number(0, 1, true));
  cli.app()
      .add_option("--force-filter", p.mpc.force_filter,
                  "the MPC's low-pass of the estimated force [s] (0: none)")
      ->capture_default_str()
      ->check(concert::cli::number(0.0, 5.0));
  cli.app()
      .add_option("--slot-match", p.mpc.slot_match,
                  "an obstacle keeps its constraint slot within this distance [m] (0: the grid's "
                  "order)")
      ->capture_default_str()
      ->check(concert::cli::number(0.0, 5.0));
  cli.app().add_flag("--cart", p.cart, "a cart pushed along the route the other way");
  cli.app()
      .add_option("--object-mass", p.object_mass,
                  "the object's weight hangs from the TCP from lift until open [kg]")
      ->capture_default_str()
      ->check(concert::cli::number(0.0, 50.0));
  cli.app().add_option("--trace", trace,
                       "write every solve (iterations, CPU and wall ms, warm, estimated and true "
                       "force) to this CSV file");
  cli.on_run(cli.app(), [&] {
    p.mpc_knows_period = knows_period != 0;
    return bench(p, trace);
  });
  return cli.run(argc, argv);
}
