// Tree -> model (URDF + SRDF + controller config + hash) and scan -> model, for the public
// database's 18-module robot and synthetic 100 / 1 000-module trees. Not a test.
//   bench_modelgen [--benchmark_filter=...]   (Google Benchmark flags; --help lists them)

#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

#include "concert/cli/benchmark_main.hpp"
#include "concert/simbus/assembly.hpp"
#include "concert/topology/reconstruction.hpp"
#include "modelgen/model_generator.hpp"

namespace fs = std::filesystem;
using namespace concert;

namespace {

const fs::path kPublic = fs::path(CONCERT_SHARED_DATA) / "concert_resources";

const module_db::ModuleDatabase& db() {
  static const module_db::ModuleDatabase d = module_db::load_module_database(kPublic);
  return d;
}

topology::ModuleNode node(int index, const std::string& key, int parent, int connector) {
  topology::ModuleNode n;
  n.index = index;
  n.key = key;
  n.parent_module = parent;
  n.parent_connector = connector;
  return n;
}

topology::ModuleTree eighteen() {
  const simbus::Assembly a = simbus::load_assembly(fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml");
  return simbus::tree_from_assembly(a, topology::EscCatalog::load(kPublic));
}

/// A seeded random tree of `n` modules: mobile base, then joints, links and torso hubs hung on
/// free output connectors, end-effectors closing some chains.
topology::ModuleTree synthetic(int n, unsigned seed) {
  std::mt19937 rng(seed);
  topology::ModuleTree t;
  t.modules.push_back(node(0, "mobile_platform_concert", -1, -1));
  struct Free {
    int module;
    int connector;
  };
  std::vector<Free> free{{0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}};
  const char* bodies[] = {"module_joint_yaw_A_concert", "module_joint_elbow_A_concert", "module_joint_yaw_B_concert",
                          "module_joint_elbow_B_concert", "module_link_straight_400_concert", "module_link_elbow_45_concert"};
  const char* tools[] = {"module_drill_concert", "passive_end_effector_panel", "module_spraying_tool_concert"};
  while (static_cast<int>(t.modules.size()) < n && !free.empty()) {
    const size_t pick = std::uniform_int_distribution<size_t>(0, free.size() - 1)(rng);
    const Free slot = free[pick];
    free.erase(free.begin() + static_cast<long>(pick));
    const int index = static_cast<int>(t.modules.size());
    const int r = std::uniform_int_distribution<int>(0, 99)(rng);
    std::string key;
    if (r < 8) {
      key = "module_Y_torso_concert";
      free.push_back({index, 1});
      free.push_back({index, 2});
    } else if (r < 14 && free.size() > 3) {
      key = tools[r % 3];
    } else {
      key = bodies[r % 6];
      free.push_back({index, 1});
    }
    t.modules.push_back(node(index, key, slot.module, slot.connector));
  }
  return t;
}

void BM_TreeToModel(benchmark::State& state, const topology::ModuleTree& tree) {
  const modelgen::ModelGenerator gen(db());
  size_t bytes = 0;
  for (auto _ : state) {
    modelgen::GeneratedModel m = gen.generate(tree);
    bytes = m.urdf.size() + m.srdf.size() + m.config_yaml.size();
    benchmark::DoNotOptimize(m.content_hash);
  }
  state.counters["modules"] = static_cast<double>(tree.modules.size());
  state.counters["text_kB"] = static_cast<double>(bytes) / 1024.0;
}

void BM_ScanToModel18(benchmark::State& state) {
  const auto catalog = topology::EscCatalog::load(kPublic);
  const simbus::Assembly a = simbus::load_assembly(fs::path(SIMBUS_EXAMPLES) / "concert_paper_robot.yaml");
  const topology::EscScan scan = simbus::simulate_scan(a, catalog);
  const topology::Discovery disc(catalog);
  const modelgen::ModelGenerator gen(db());
  for (auto _ : state) {
    modelgen::GeneratedModel m = gen.generate(disc.run(scan));
    benchmark::DoNotOptimize(m.content_hash);
  }
}

void BM_LoadPublicDatabase(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(module_db::load_module_database(kPublic).size());
}

}  // namespace

BENCHMARK_CAPTURE(BM_TreeToModel, paper_18_modules, eighteen())->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TreeToModel, synthetic_100, synthetic(100, 1))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TreeToModel, synthetic_1000, synthetic(1000, 2))->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScanToModel18)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LoadPublicDatabase)->Unit(benchmark::kMillisecond);
int main(int argc, char** argv) {
  return concert::cli::benchmark_main(
      "bench_modelgen", "Tree -> model (URDF + SRDF + controller config + hash) and scan -> model.",
      argc, argv);
}
