// Global planner and closed-loop navigation benchmark.
//   bench_global_planner [MAP_YAML] [--pairs N] [--missions N] [--seed S]
// Without MAP_YAML: a synthetic storey of 4 x 3 rooms of 5 m with 1 m doors at 5 cm cells
// (403 x 303 = 122k cells, about the largest shared storey). Prints plan time (median, p95)
// over seeded start/goal pairs, costmap build and scan update times, then success rate and
// time to goal over seeded missions with unmapped obstacles in the kinematic simulation.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "planning_fixtures.hpp"

namespace nav = concert::nav;
namespace nt = concert::nav::testing;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

void table_header() {
  std::printf("| %-28s | %9s | %9s | %9s | %-4s |\n", "", "median", "p95", "max", "unit");
  std::printf("|------------------------------|-----------|-----------|-----------|------|\n");
}

void row(const char* name, const std::vector<double>& v, const char* unit) {
  std::printf("| %-28s | %9.2f | %9.2f | %9.2f | %-4s |\n", name, quantile(v, 0.5),
              quantile(v, 0.95), v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()), unit);
}

int bench(const std::string& map_yaml, int pairs, int missions, unsigned seed) {
  nt::Building building;
  try {
    if (map_yaml.empty()) {
      building = nt::make_building(4, 3, 5.0, 0.15, 1.0, 0.05, seed);
    } else {
      building.map = concert::bim::load_map(map_yaml);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_global_planner: %s\n", e.what());
    return 1;
  }
  const auto& map = building.map;
  std::printf("map: %s, %d x %d cells = %d at %.3f m (robot 0.7 x 0.5 m)\n",
              map_yaml.empty() ? "synthetic 4 x 3 rooms" : map_yaml.c_str(), map.width, map.height,
              map.width * map.height, map.resolution);

  const nav::RobotShape shape = nt::test_robot();
  std::vector<double> build_ms;
  for (int k = 0; k < 5; ++k) {
    const Clock::time_point t0 = Clock::now();
    const nav::Costmap c(map, shape, {});
    build_ms.push_back(ms_since(t0));
  }
  nav::Costmap costmap(map, shape, {});
  std::mt19937 rng(seed);
  const auto plan_pairs = nt::random_pairs(costmap, pairs, 5.0, rng);

  std::vector<double> scan_ms;
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector2d o =
        plan_pairs[static_cast<std::size_t>(k) % plan_pairs.size()].first.head<2>();
    const auto beams = nt::cast_scan(map, o, 720, 8.0);
    const Clock::time_point t0 = Clock::now();
    costmap.update_obstacles(o, beams);
    scan_ms.push_back(ms_since(t0));
  }
  costmap.clear_obstacles();

  nav::GlobalPlanner planner;
  std::vector<double> total_ms, search_ms, expansions, length;
  int failed = 0;
  for (const auto& [s, g] : plan_pairs) {
    const nav::PlanResult r = planner.plan(costmap, s, g);
    if (!r.ok()) {
      ++failed;
      continue;
    }
    total_ms.push_back(1e3 * r.total_time);
    search_ms.push_back(1e3 * r.search_time);
    expansions.push_back(r.expansions);
    length.push_back(r.length);
  }
  std::printf("\nGlobal planner: %d seeded start/goal pairs >= 5 m apart (seed %u), %d failed\n\n",
              pairs, seed, failed);
  table_header();
  row("plan time (search + smooth)", total_ms, "ms");
  row("A* search time", search_ms, "ms");
  row("expansions", expansions, "");
  row("path length", length, "m");
  row("costmap build (whole map)", build_ms, "ms");
  row("scan update (720 beams)", scan_ms, "ms");

  if (!map_yaml.empty() || missions <= 0) return 0;
  // Missions with unmapped obstacles (1-2 boxes on the planned path, away from doors).
  std::vector<double> time_to_goal, pos_err, yaw_err, replans;
  int reached = 0;
  int collided = 0;
  const auto mission_pairs = nt::random_pairs(costmap, missions, 4.0, rng);
  for (std::size_t k = 0; k < mission_pairs.size(); ++k) {
    const auto& [s, g] = mission_pairs[k];
    const nav::PlanResult plan = planner.plan(costmap, s, g);
    if (!plan.ok()) continue;
    concert::bim::OccupancyGrid truth = map;
    std::uniform_int_distribution<int> count(1, 2);
    nt::add_obstacles_on_path(truth, plan.path, building.doors, count(rng), 1.3, rng);
    nt::SimConfig config;
    config.seed = static_cast<std::uint32_t>(seed * 1000 + k);
    const nt::RunResult r = nt::run_mission(map, truth, s, g, config);
    collided += r.collided ? 1 : 0;
    if (r.reached) {
      ++reached;
      time_to_goal.push_back(r.time);
      pos_err.push_back(1e3 * r.position_error);
      yaw_err.push_back(r.heading_error * 180.0 / M_PI);
      replans.push_back(r.replans);
    } else {
      std::printf("mission %zu failed: %s\n", k, r.failure.c_str());
    }
  }
  std::printf(
      "\nClosed loop (omni, kinematic sim, 0.5 m/s, unmapped obstacles): %d/%zu reached, "
      "%d collisions\n\n",
      reached, mission_pairs.size(), collided);
  table_header();
  row("time to goal (simulated)", time_to_goal, "s");
  row("position error at goal", pos_err, "mm");
  row("heading error at goal", yaw_err, "deg");
  row("replans", replans, "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_global_planner",
                        "Global planner (plan time over seeded start/goal pairs, costmap build and "
                        "scan update) and closed-loop navigation (seeded missions with unmapped "
                        "obstacles in the kinematic simulation).",
                        std::cout, std::cerr);
  std::string map_yaml;
  int pairs = 100;
  int missions = 20;
  unsigned seed = 1;
  auto& app = cli.app();
  app.add_option("MAP_YAML", map_yaml,
                 "storey map (default: a synthetic storey of 4 x 3 rooms of 5 m at 5 cm cells)")
      ->check(CLI::ExistingFile);
  app.add_option("--pairs", pairs, "seeded start/goal pairs planned")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1e6, true));
  app.add_option("--missions", missions,
                 "seeded closed-loop missions (synthetic storey only; 0: none)")
      ->capture_default_str()
      ->check(concert::cli::number(0, 1e6, true));
  app.add_option("--seed", seed, "seed of the storey, the pairs and the missions")
      ->capture_default_str()
      ->check(concert::cli::number(0, 4294967295.0, true));
  cli.on_run(app, [&] { return bench(map_yaml, pairs, missions, seed); });
  return cli.run(argc, argv);
}
