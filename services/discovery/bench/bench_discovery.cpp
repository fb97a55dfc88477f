// Scan -> module tree: the paper robot (19 ESCs) and synthetic trees of 100 .. 10 000 slaves,
// linear reconstruction vs. the paper's Algorithms 1+2. Run: bench_discovery
// [--benchmark_filter=...]. Not a test: no timing assertion anywhere.
#include <benchmark/benchmark.h>

#include <random>
#include <string>

#include "concert/cli/benchmark_main.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/simbus/testing.hpp"
#include "concert/topology/reconstruction.hpp"

namespace {

using concert::topology::Discovery;
using concert::topology::EscCatalog;
using concert::topology::EscScan;
using concert::topology::PortOrder;

const EscCatalog& public_catalog() {
  static const EscCatalog catalog =
      EscCatalog::load(std::string(CONCERT_SHARED_DATA) + "/concert_resources");
  return catalog;
}

EscScan paper_scan() {
  const auto assembly = concert::simbus::load_assembly(
      std::string(CONCERT_SOURCE_DIR) + "/libs/simbus/examples/concert_paper_robot.yaml");
  return concert::simbus::simulate_scan(assembly, public_catalog());
}

/// A synthetic scan of about `slaves` ESCs: chains with hubs (chain_bias 0.8).
EscScan synthetic_scan(int64_t slaves, double chain_bias) {
  const EscCatalog catalog = concert::simbus::synthetic_catalog();
  std::mt19937 rng(42);
  concert::simbus::RandomAssemblyParams params;
  params.chain_bias = chain_bias;
  params.hub_bias = 0.1;
  // Modules hold 1..3 ESCs; grow the module count until the scan has enough slaves.
  params.modules = static_cast<int32_t>(slaves * 9 / 10);
  EscScan scan;
  do {
    rng.seed(42);
    scan = concert::simbus::simulate_scan(concert::simbus::random_assembly(catalog, rng, params),
                                          catalog);
    params.modules += static_cast<int32_t>(slaves / 50 + 1);
  } while (static_cast<int64_t>(scan.slaves.size()) < slaves);
  return scan;
}

void BM_PaperRobotDiscovery(benchmark::State& state) {
  const EscScan scan = paper_scan();
  const Discovery discovery(public_catalog());
  for (auto _ : state) benchmark::DoNotOptimize(discovery.run(scan));
  state.counters["slaves"] = static_cast<double>(scan.slaves.size());
}
BENCHMARK(BM_PaperRobotDiscovery)->Unit(benchmark::kMicrosecond);

void BM_PaperRobotCatalogueAndDiscovery(benchmark::State& state) {
  // Including building the Discovery (layouts of every catalogue entry) each time.
  const EscScan scan = paper_scan();
  for (auto _ : state) {
    const Discovery discovery(public_catalog());
    benchmark::DoNotOptimize(discovery.run(scan));
  }
}
BENCHMARK(BM_PaperRobotCatalogueAndDiscovery)->Unit(benchmark::kMicrosecond);

void BM_SyntheticDiscovery(benchmark::State& state) {
  const EscScan scan = synthetic_scan(state.range(0), 0.8);
  const Discovery discovery(concert::simbus::synthetic_catalog());
  for (auto _ : state) benchmark::DoNotOptimize(discovery.run(scan));
  state.counters["slaves"] = static_cast<double>(scan.slaves.size());
  state.SetComplexityN(static_cast<int64_t>(scan.slaves.size()));
}
BENCHMARK(BM_SyntheticDiscovery)
    ->Arg(100)->Arg(1000)->Arg(10000)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();

/// Times graph-chi reconstruction of `scan` (linear, or the paper's reference algorithm).
template <bool kReference>
void time_network(benchmark::State& state, const EscScan& scan) {
  for (auto _ : state) {
    if constexpr (kReference) {
      benchmark::DoNotOptimize(
          concert::topology::reconstruct_network_reference(scan, PortOrder::kReal0312));
    } else {
      benchmark::DoNotOptimize(
          concert::topology::reconstruct_network(scan, PortOrder::kReal0312));
    }
  }
  state.counters["slaves"] = static_cast<double>(scan.slaves.size());
  state.SetComplexityN(static_cast<int64_t>(scan.slaves.size()));
}

template <bool kReference>
void BM_Network(benchmark::State& state) {
  // Graph chi only; long chains are the paper algorithm's worst case (it walks back over
  // whole subtrees for each slave hanging on a hub after them).
  const EscScan scan =
      concert::topology::checked_scan(synthetic_scan(state.range(0), 0.95));
  time_network<kReference>(state, scan);
}
BENCHMARK(BM_Network<false>)->Name("BM_NetworkLinear")
    ->Arg(18)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity();
BENCHMARK(BM_Network<true>)->Name("BM_NetworkPaperReference")
    ->Arg(18)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity();

/// The paper algorithm's worst case: a chain of split points, each with a leaf on its second
/// port; every leaf comes after the whole rest of the chain in the ring, so Algorithm 1 walks
/// back over it. n = 2k + 1 slaves.
EscScan comb_scan(int64_t slaves) {
  const int64_t k = slaves / 2;
  EscScan scan;
  for (int64_t i = 0; i < 2 * k + 1; ++i) {
    concert::topology::EscSlave s;
    s.position = static_cast<int32_t>(i + 1);
    s.active_ports = i < k ? 0b1011 : 0b0001;
    s.topology = i < k ? 3 : 1;
    scan.slaves.push_back(s);
  }
  return scan;
}

template <bool kReference>
void BM_NetworkComb(benchmark::State& state) {
  const EscScan scan = comb_scan(state.range(0));
  time_network<kReference>(state, scan);
}
BENCHMARK(BM_NetworkComb<false>)->Name("BM_NetworkCombLinear")
    ->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity();
BENCHMARK(BM_NetworkComb<true>)->Name("BM_NetworkCombPaperReference")
    ->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity();

}  // namespace

int main(int argc, char** argv) {
  return concert::cli::benchmark_main(
      "bench_discovery",
      "Scan -> module tree: the paper robot and synthetic trees of 100 .. 10 000 slaves.", argc,
      argv);
}
