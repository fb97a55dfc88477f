// Localiser benchmark: update time per scan (median, p95) and localisation error along the
// seeded > 30 m route of the test storey (two rooms, a door, boxes that are not in the map), at
// 1000 and 3000 particles. The scans are ray-cast outside the timed region.
//   bench_localiser [seed]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <random>
#include <vector>

#include "concert/cli/cli.hpp"
#include "localiser_sim.hpp"
#include "nav/localiser.hpp"

namespace {

using concert::nav::LikelihoodField;
using concert::nav::Localiser;
using concert::nav::LocaliserParams;
using concert::nav::LocaliserStatus;
using concert::nav::PlanarScan;
namespace testing = concert::nav::testing;

struct Row {
  int particles{0};
  std::size_t scans{0};
  double median_ms{0.0};
  double p95_ms{0.0};
  double mean_error{0.0};
  double max_error{0.0};
  double max_yaw_error{0.0};
  std::size_t tracking{0};
};

double percentile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  return values[index];
}

int bench(std::uint64_t seed) {
  const auto field = std::make_shared<const LikelihoodField>(
      testing::rasterise(testing::storey_walls(), 0.05, {0.021, 0.037}));
  std::vector<testing::Rect> world_rects = testing::storey_walls();
  for (const testing::Rect& r : testing::unmapped_boxes()) world_rects.push_back(r);
  const concert::bim::OccupancyGrid world = testing::rasterise(world_rects, 0.01);

  const std::vector<Eigen::Vector3d> truth = testing::route();
  std::mt19937_64 rng(seed);
  const std::vector<Eigen::Vector3d> odom =
      testing::drifting_odometry(truth, rng, {3.0, -2.0, 0.7});
  std::vector<PlanarScan> scans;
  scans.reserve(truth.size());
  for (const Eigen::Vector3d& pose : truth)
    scans.push_back(testing::simulate_scan(world, pose, rng));

  std::vector<Row> rows;
  for (int particles : {1000, 3000}) {
    LocaliserParams params;
    params.particles = particles;
    params.seed = seed;
    Localiser localiser(field, params);
    localiser.set_pose(truth[0] + Eigen::Vector3d(0.15, -0.13, 0.05), {0.2, 0.2, 0.1}, odom[0]);
    Row row;
    row.particles = particles;
    row.scans = truth.size();
    std::vector<double> times;
    double sum = 0.0;
    std::size_t counted = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      const auto& e = localiser.update(odom[i], scans[i]);
      const auto t1 = std::chrono::steady_clock::now();
      times.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      row.tracking += e.status == LocaliserStatus::kTracking ? 1 : 0;
      if (i < 10) continue;  // converging from the user's initial pose
      const Eigen::Vector2d err = testing::pose_error(e.pose, truth[i]);
      sum += err.x();
      ++counted;
      row.max_error = std::max(row.max_error, err.x());
      row.max_yaw_error = std::max(row.max_yaw_error, err.y());
    }
    row.mean_error = sum / static_cast<double>(counted);
    row.median_ms = percentile(times, 0.5);
    row.p95_ms = percentile(times, 0.95);
    rows.push_back(row);
  }

  std::printf(
      "Localiser along a %.1f m route (%zu scans of 720 bins at 10 Hz, 5 cm map, "
      "4 unmapped boxes, seed %llu)\n\n",
      testing::route_length(truth), truth.size(), static_cast<unsigned long long>(seed));
  std::printf(
      "| particles | update median [ms] | update p95 [ms] | mean error [cm] | max error [cm] "
      "| max yaw error [deg] | scans tracking |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    std::printf("| %d | %.2f | %.2f | %.1f | %.1f | %.2f | %zu/%zu |\n", r.particles, r.median_ms,
                r.p95_ms, 100.0 * r.mean_error, 100.0 * r.max_error,
                r.max_yaw_error * 180.0 / 3.141592653589793, r.tracking, r.scans);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_localiser",
                        "Localiser update time per scan and localisation error along the seeded "
                        "route of the test storey, at 1000 and 3000 particles.",
                        std::cout, std::cerr);
  std::uint64_t seed = 1;
  cli.app()
      .add_option("seed", seed, "seed of the odometry drift and the scans' noise")
      ->capture_default_str()
      ->check(concert::cli::count());
  cli.on_run(cli.app(), [&seed] { return bench(seed); });
  return cli.run(argc, argv);
}
