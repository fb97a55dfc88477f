// Benchmark of the drilling service on whole simulated stacks (issue #17; paper section 6.1): the
// paper's scenarios run as missions, the holes the simulator's wall records scored against the
// marks' truth. Cameras with their noise, every service a process on this machine.
//   blobs     scenario 1: six blue blobs in four clusters, 0.95-2.15 m high, morphology B
//             (deploy/bench/drill_blobs_*.yaml; visual servoing)
//   patterns  scenario 3, the part morphology A reaches: four ArUco 60 cm rows at 0.5-2.0 m
//             (deploy/bench/drill_patterns_*.yaml; the kinematics alone)
//   high      scenario 3 above 2.4 m: two ArUco 60 cm rows at 2.5 and 2.9 m, morphology C (the
//             Passive Base Link, as the paper drills there; deploy/bench/drill_high_*.yaml)
//   bim       scenario 2: the FZK house's ground floor (IFC), an area picked on a wall of the
//             building's model, two blue blobs 0.1 m apart drawn there; the robot (morphology A)
//             starts in another part of the room, navigates to the BIM base pose, then drills
//   row       one row of scenario 3 (the marker at 1.65 m of deploy/bench/drill_patterns_site.yaml,
//             morphology A): the patterns scenario in two minutes, to measure its spread
//   low       the row at 0.5 m of the same site alone (morphology A): no posture holds the full
//             thrust there, the holes are drilled at half of it or less (light_drilling)
//   lowest    scenario 3's lowest row, 0.35 m (the marker at 0.5 m, morphology A;
//             deploy/bench/drill_lowest_site.yaml): drilled at 39-52 % of the thrust
//   demo      the demo wall's pattern (deploy/demo/drill_site.yaml)
// Usage: bench_drill_mission [--scenario blobs|patterns|high|row|low|lowest|bim|demo|all] [--runs N] [--assembly FILE] [--logs] [--map world|sensors|both]
//        (default: all, 1, each scenario's robot)
// Prints per hole the error in the wall's plane, then per scenario: holes drilled / holes
// marked, error median / p95 / max, and the mission time split. Minutes per run.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <optional>

#include "concert/cli/cli.hpp"
#include "drill_runner.hpp"

using namespace concert::system_test;
using concert::msg::DrillStatus;

namespace {

struct Scenario {
  std::string name, assembly, site;
  std::string mission;  // a mission file, or with `text` the mission itself
  bool text{false};
  std::optional<Building> building;  // scenario 2: the site is made from the IFC storey
};


std::string source(const std::string& path) { return std::string(CONCERT_SOURCE_DIR) + "/" + path; }

std::string read(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double at = p * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

int bench(const std::string& which, int runs, const std::string& assembly, bool logs,
          const std::string& map) {
  const std::vector<Scenario> all{
      {"blobs", source("services/planner/data/morphology_b.yaml"),
       source("deploy/bench/drill_blobs_site.yaml"), source("deploy/bench/drill_blobs_mission.yaml")},
      {"patterns", source("services/planner/data/morphology_a.yaml"),
       source("deploy/bench/drill_patterns_site.yaml"), source("deploy/bench/drill_patterns_mission.yaml")},
      {"high", source("services/planner/data/morphology_c.yaml"),
       source("deploy/bench/drill_high_site.yaml"), source("deploy/bench/drill_high_mission.yaml")},
      {"row", source("services/planner/data/morphology_a.yaml"),
       source("deploy/bench/drill_patterns_site.yaml"),
       "name: bench row\ndepth: 0.03\nareas:\n  - {name: row_150, marks: aruco, point: [2.2, -0.3, 1.65]}\n",
       true},
      {"low", source("services/planner/data/morphology_a.yaml"),
       source("deploy/bench/drill_patterns_site.yaml"),
       "name: bench low\ndepth: 0.03\nareas:\n  - {name: row_050, marks: aruco, point: [2.2, 0.9, 0.65]}\n",
       true},
      {"lowest", source("services/planner/data/morphology_a.yaml"),
       source("deploy/bench/drill_lowest_site.yaml"),
       "name: bench lowest\ndepth: 0.03\nareas:\n  - {name: row_035, marks: aruco, point: [2.2, 0.9, 0.50]}\n",
       true},
      {"bim", source("services/planner/data/morphology_a.yaml"), "", bim_mission("bench bim area"),
       true, fzk_living_room()},
      {"demo", source("deploy/demo/drill_robot.yaml"), source("deploy/demo/drill_site.yaml"),
       "name: bench demo pattern\ndepth: 0.03\nareas:\n"
       "  - {name: pattern, marks: aruco, point: [2.2, -0.9, 1.45]}\n",
       true},
  };
  const concert::drill::PatternTable patterns =
      concert::drill::load_patterns(source("services/drill/config/patterns.yaml"));
  bool known = false;
  for (const Scenario& sc : all) {
    // all: row and low are in patterns
    if (which == "all" ? sc.name == "row" || sc.name == "low" : which != sc.name) continue;
    known = true;
    const std::string mission = sc.text ? sc.mission : read(sc.mission);
    const std::string site = sc.building ? building_site(*sc.building) : sc.site;
    std::vector<Target> targets = targets_of(concert::world::load_world_file(site), patterns);
    if (sc.name == "demo") {  // the demo wall's blobs are another mission's
      std::erase_if(targets, [](const Target& t) { return t.name.rfind("blob", 0) == 0; });
    }
    if (sc.name == "row" || sc.name == "low") {  // the wall's other rows are the patterns scenario's
      const std::string row = sc.name == "row" ? "row_150" : "row_050";
      std::erase_if(targets, [&row](const Target& t) { return t.name.rfind(row, 0) != 0; });
    }
    std::vector<double> errors;
    std::size_t drilled = 0, marked = 0;
    double t_nav = 0, t_plan = 0, t_exec = 0, t_drill = 0, t_total = 0;
    for (int r = 0; r < runs; ++r) {
      const MissionRun run = run_mission(assembly.empty() ? sc.assembly : assembly, site, mission,
                                         std::chrono::seconds(3600), sc.building, map);
      if (!run.status) {
        std::cerr << sc.name << " run " << r + 1 << ": no status from the drill service" << run.logs
                  << "\n";
        marked += targets.size();
        continue;
      }
      const DrillStatus& s = *run.status;
      std::printf("%s run %d: mission %s, %u of %u marked holes drilled, safety %s%s%s\n",
                  sc.name.c_str(), r + 1,
                  s.state() == concert::msg::DRILL_SUCCEEDED ? "succeeded" : "did not succeed",
                  s.holes_drilled(), s.holes_marked(), run.safety_running ? "RUNNING" : "STOPPED",
                  s.reason().empty() ? "" : ": ", s.reason().c_str());
      bool off = false;  // a hole past 5 mm, or a mark not drilled: the logs say why
      for (const Target& t : targets) {
        marked += 1;
        const auto [hole, e] = nearest_hole(run.holes, t);
        // A hole within 5 cm is this mark's; farther, the mark was not drilled.
        if (hole == nullptr || e.norm() > 0.05) {
          std::printf("  %-22s not drilled\n", t.name.c_str());
          off = true;
          continue;
        }
        off = off || e.norm() > 0.005;
        drilled += 1;
        errors.push_back(e.norm());
        std::printf("  %-22s x %+6.2f mm  y %+6.2f mm  |e| %5.2f mm  depth %4.1f mm\n",
                    t.name.c_str(), e.horizontal * 1e3, e.vertical * 1e3, e.norm() * 1e3,
                    hole->depth() * 1e3);
      }
      if (logs || off || s.state() != concert::msg::DRILL_SUCCEEDED) {
        std::cerr << sc.name << " run " << r + 1 << ": the services' logs" << run.logs << "\n";
      }
      t_nav += s.time_navigate();
      t_plan += s.time_plan();
      t_exec += s.time_execute();
      t_drill += s.time_drill();
      t_total += s.time_total();
      std::fflush(stdout);
    }
    std::printf(
        "== %s (%d run%s): %zu of %zu marked holes drilled; error median %.2f mm, p95 %.2f mm, "
        "max %.2f mm; time per run: navigate %.0f s, plan %.0f s, execute %.0f s, drill %.0f s, "
        "total %.0f s\n",
        sc.name.c_str(), runs, runs == 1 ? "" : "s", drilled, marked, percentile(errors, 0.5) * 1e3,
        percentile(errors, 0.95) * 1e3, percentile(errors, 1.0) * 1e3, t_nav / runs, t_plan / runs,
        t_exec / runs, t_drill / runs, t_total / runs);
  }
  if (!known) {
    std::cerr << "bench_drill_mission: unknown scenario '" << which
              << "' (blobs, patterns, high, row, low, lowest, bim, demo or all)\n";
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli("bench_drill_mission",
                        "The paper's drilling scenarios as missions on whole simulated stacks, the "
                        "holes scored against the marks' truth. Minutes per run.",
                        std::cout, std::cerr);
  std::string which = "all";
  int runs = 1;
  auto& app = cli.app();
  concert::cli::Cli::add_choice(app, "--scenario", which, {"blobs", "patterns", "high", "row", "low", "lowest", "bim", "demo", "all"},
                                "scenario to run")
      ->capture_default_str();
  std::string assembly;
  app.add_option("--assembly", assembly,
                 "the robot of every scenario run (default: the scenario's, e.g. morphology A "
                 "for bim)")
      ->check(CLI::ExistingFile);
  app.add_option("--runs", runs, "runs per scenario")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1e6, true));
  std::string map = "world";
  concert::cli::Cli::add_choice(app, "--map", map, {"world", "sensors", "both"},
                                "the planner's map: the simulated world's description, the robot's lidars and "
                                "depth cameras, or both (concert_planner --map)")
      ->capture_default_str();
  bool logs = false;
  app.add_flag("--logs", logs, "print the services' logs after every run (default: after a failed one, or one with a hole past 5 mm)");
  cli.on_run(app, [&] { return bench(which, runs, assembly, logs, map); });
  return cli.run(argc, argv);
}
