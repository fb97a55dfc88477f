// Benchmark (not a test): IFC import time per shared file (the web-ifc step in Node.js plus
// reading its output) and the storey map rasterisation time at 5 cm cells.
//   bench_bim_import [--benchmark_repetitions=N ...]
#include <benchmark/benchmark.h>

#include <string>

#include "concert/bim/model.hpp"
#include "concert/bim/storey_map.hpp"
#include "concert/cli/benchmark_main.hpp"

namespace {

using concert::bim::BimModel;

std::string bim_file(const std::string& name) {
  return std::string(CONCERT_SHARED_DATA) + "/bim/" + name;
}

void import_file(benchmark::State& state, const std::string& name) {
  std::size_t elements = 0;
  for (auto _ : state) {
    const BimModel m = concert::bim::load_ifc(bim_file(name));
    elements = m.elements.size();
    benchmark::DoNotOptimize(elements);
  }
  state.counters["elements"] = static_cast<double>(elements);
}

void rasterise(benchmark::State& state, const std::string& name, const std::string& storey) {
  const BimModel m = concert::bim::load_ifc(bim_file(name));
  const auto& s = m.storey(storey);
  std::size_t cells = 0;
  for (auto _ : state) {
    const auto grid = concert::bim::storey_map(m, s);
    cells = grid.cells.size();
    benchmark::DoNotOptimize(cells);
  }
  state.counters["cells"] = static_cast<double>(cells);
}

BENCHMARK_CAPTURE(import_file, fzk_haus, std::string("AC20-FZK-Haus.ifc"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(import_file, duplex, std::string("duplex.ifc"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(import_file, ifc_open_house, std::string("IfcOpenHouse_IFC4.ifc"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(rasterise, fzk_erdgeschoss, std::string("AC20-FZK-Haus.ifc"),
                  std::string("Erdgeschoss"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(rasterise, duplex_level_1, std::string("duplex.ifc"), std::string("Level 1"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(rasterise, duplex_level_2, std::string("duplex.ifc"), std::string("Level 2"))
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return concert::cli::benchmark_main(
      "bench_bim_import",
      "IFC import time per shared file and the storey map rasterisation time at 5 cm cells.", argc,
      argv);
}
