// Chaos benchmark: the random phase of system_chaos_test for longer. The stack runs under
// `concert up` in simulation with the task running (tests/system/chaos.hpp); one or two random
// services are killed with SIGKILL at random moments, round after round, for the duration.
// Prints every round, then kill -> ready at the current model per service (median, max), the
// task's requests (succeeded, failed for a stop, lost) and the false stops.
// Usage: bench_chaos [--seed N (1)] [--duration S (300)]   (domain: CONCERT_DOMAIN_ID, default 197)
#include <cstdlib>
#include <iostream>
#include <random>
#include <stdexcept>
#include <string>

#include "chaos.hpp"
#include "concert/cli/cli.hpp"
#include "process.hpp"

namespace {

int bench(unsigned seed, double duration_s) {
  using namespace concert::system_test::chaos;
  if (std::getenv("CONCERT_DOMAIN_ID") == nullptr) setenv("CONCERT_DOMAIN_ID", "47", 1);
  concert::testing::TempDir run("concert-bench-chaos");
  Chaos chaos(demo_options(run.path()));
  for (const auto& f : chaos.start()) {
    std::cerr << "bench_chaos: " << f << "\n";
    return 1;
  }
  std::cout << "bench_chaos: seed " << seed << ", " << duration_s << " s of random kills"
            << std::endl;
  std::mt19937 rng(seed);
  std::vector<RoundReport> rounds;
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(duration_s));
  while (Clock::now() < until) rounds.push_back(chaos.random_round(rng));
  const TaskReport task = chaos.stop();

  int failed = 0, false_stops = 0, stops = 0, starved = 0;
  for (const auto& r : rounds) {
    failed += r.failures.empty() ? 0 : 1;
    stops += r.stopped ? 1 : 0;
    starved += static_cast<int>(r.starved.size());
    for (const auto& f : r.failures) false_stops += f.rfind("false stop", 0) == 0 ? 1 : 0;
  }
  std::cout << "\n"
            << rounds.size() << " rounds, " << failed << " with a failure; " << stops << " stops, "
            << false_stops << " false stops, " << starved
            << " stop causes naming a starved service (its heartbeats went quiet here too)\n"
            << "kill -> ready at the current model:\n"
            << figures(rounds) << summary(task, rounds);
  return failed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli(
      "bench_chaos",
      "The random phase of system_chaos_test for longer: the stack under `concert "
      "up` in simulation, random services killed with SIGKILL round after round. "
      "Domain: CONCERT_DOMAIN_ID, default 197.",
      std::cout, std::cerr);
  unsigned seed = 1;
  double duration_s = 300.0;
  auto& app = cli.app();
  app.add_option("--seed", seed, "seed of the kills")
      ->capture_default_str()
      ->check(concert::cli::number(0, 4294967295.0, true));
  app.add_option("--duration", duration_s, "how long to kill services [s]")
      ->capture_default_str()
      ->check(concert::cli::positive_seconds());
  cli.on_run(app, [&] { return bench(seed, duration_s); });
  return cli.run(argc, argv);
}
