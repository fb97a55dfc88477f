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
//   experiments  scenario 3 as the paper ran it: 22 missions of one 60 cm row each, heights
//             0.35-2.90 m evenly, morphology A up to 2.4 m and C above, a fresh stack each
//             (not in all: about 90 minutes)
//   generated  drilling sites nobody rehearsed, drawn from --seed (tests/system/drill_sites.hpp):
//             --count walls at a yaw within +-0.25 rad 1.6-2.8 m away, a blob pair or an ArUco
//             marker of any pattern at 0.4-2.6 m, boxes beside the area; morphology A, C above
//             2.4 m; one mission on a fresh stack each (not in all: 3-8 minutes a site)
// CONCERT_STACK_DIR=DIR runs the services' binaries of that name in DIR (a copy taken before a
// long run, so that building on meanwhile does not change them).
// Usage: bench_drill_mission [--scenario blobs|patterns|high|row|low|lowest|bim|demo|experiments|generated|all]
//          [--runs N] [--assembly FILE] [--logs] [--map world|sensors|both] [--seed S [--first K] --count N]
//        (default: all, 1, each scenario's robot)
// Prints per hole the error in the wall's plane, then per scenario: holes drilled / holes
// marked, error median / p95 / max, and the mission time split. Minutes per run.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"
#include "drill_runner.hpp"
#include "drill_sites.hpp"

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

// Holes and times summed over runs.
struct Tally {
  std::vector<double> errors;  // [m] in the wall's plane, of the holes drilled
  std::size_t drilled{0}, marked{0};
  std::size_t reachable{0}, judged_unreachable{0};  // as the report judged them before moving
  double nav{0}, plan{0}, exec{0}, drill{0}, total{0};  // [s]
  int safety_stops{0};
  // [s] summed over the areas and holes of the report (AreaTimes, HoleTimes)
  double approach{0}, detect{0}, survey{0}, place{0}, align{0}, feed{0}, retract{0};

  Tally& operator+=(const Tally& o) {
    errors.insert(errors.end(), o.errors.begin(), o.errors.end());
    drilled += o.drilled;
    marked += o.marked;
    reachable += o.reachable;
    judged_unreachable += o.judged_unreachable;
    nav += o.nav;
    plan += o.plan;
    exec += o.exec;
    drill += o.drill;
    total += o.total;
    safety_stops += o.safety_stops;
    approach += o.approach;
    detect += o.detect;
    survey += o.survey;
    place += o.place;
    align += o.align;
    feed += o.feed;
    retract += o.retract;
    return *this;
  }
  void print(const std::string& what, int runs) const {
    std::printf(
        "== %s: %zu of %zu marked holes drilled; reachable as the report judged: %zu of the marked "
        "(unreachable %zu), drilled %.1f %% of those; error median %.2f mm, p95 %.2f mm, max %.2f mm; "
        "time per run: navigate %.0f s, plan %.0f s, execute %.0f s, drill %.0f s, total %.0f s; "
        "%.0f s per hole drilled; %d safety stops\n",
        what.c_str(), drilled, marked, reachable, judged_unreachable,
        reachable > 0 ? 100.0 * static_cast<double>(drilled) / static_cast<double>(reachable) : std::nan(""),
        percentile(errors, 0.5) * 1e3, percentile(errors, 0.95) * 1e3,
        percentile(errors, 1.0) * 1e3, nav / runs, plan / runs, exec / runs, drill / runs, total / runs,
        drilled > 0 ? total / static_cast<double>(drilled) : std::nan(""), safety_stops);
    const double n = drilled > 0 ? static_cast<double>(drilled) : std::nan("");
    std::printf(
        "   time per hole drilled: approach %.1f s, detect %.1f s, survey %.1f s, place %.1f s, align %.1f s "
        "(posture, looks, alignment), drill %.1f s, retract %.1f s\n",
        approach / n, detect / n, survey / n, place / n, align / n, feed / n, retract / n);
    std::fflush(stdout);
  }
};

// One run scored against its marks' truth: a line per mark, the services' logs when asked or
// when something went wrong.
void score(const std::string& what, const MissionRun& run, const std::vector<Target>& targets,
           bool logs, Tally& tally) {
  if (!run.status) {
    std::cerr << what << ": no status from the drill service" << run.logs << "\n";
    tally.marked += targets.size();
    return;
  }
  const DrillStatus& s = *run.status;
  std::printf("%s: mission %s, %u of %u marked holes drilled, safety %s, %d safety stops%s%s\n", what.c_str(),
              s.state() == concert::msg::DRILL_SUCCEEDED ? "succeeded" : "did not succeed",
              s.holes_drilled(), s.holes_marked(), run.safety_running ? "RUNNING" : "STOPPED",
              run.safety_stops, s.reason().empty() ? "" : ": ", s.reason().c_str());
  for (const std::string& causes : run.stop_causes) std::printf("  safety stop: %s\n", causes.c_str());
  tally.safety_stops += run.safety_stops;
  // The report's holes: how their reach was judged, and those not drilled with the reason.
  for (const concert::msg::DrillArea& a : s.areas()) {
    tally.approach += a.time_approach();
    tally.detect += a.time_detect();
    tally.survey += a.time_survey();
    tally.place += a.time_place();
    for (const concert::msg::DrillHole& h : a.holes()) {
      tally.align += h.time_align();
      tally.feed += h.time_drill();
      tally.retract += h.time_retract();
      tally.reachable += h.reach() == concert::msg::REACH_REACHABLE;
      tally.judged_unreachable += h.reach() == concert::msg::REACH_UNREACHABLE;
      const char* reach = h.reach() == concert::msg::REACH_REACHABLE     ? "reachable"
                          : h.reach() == concert::msg::REACH_UNREACHABLE ? "unreachable"
                                                                         : "not judged";
      std::printf("  report: %s %s: %s (%s); align %.1f s, drill %.1f s, retract %.1f s%s%s\n", a.name().c_str(),
                  h.label().c_str(), reach, h.reach_reason().c_str(), h.time_align(), h.time_drill(),
                  h.time_retract(), h.state() == concert::msg::HOLE_DRILLED ? "" : "; not drilled: ",
                  h.state() == concert::msg::HOLE_DRILLED ? "" : h.reason().c_str());
    }
  }
  bool off = false;  // a hole past 5 mm, or a mark not drilled: the logs say why
  for (const Target& t : targets) {
    tally.marked += 1;
    const auto [hole, e] = nearest_hole(run.holes, t);
    // A hole within 5 cm is this mark's; farther, the mark was not drilled.
    if (hole == nullptr || e.norm() > 0.05) {
      if (hole == nullptr) {
        std::printf("  %-22s not drilled (no hole in any wall)\n", t.name.c_str());
      } else {
        std::printf("  %-22s not drilled (the nearest hole %.1f mm away: x %+.1f mm y %+.1f mm)\n", t.name.c_str(),
                    e.norm() * 1e3, e.horizontal * 1e3, e.vertical * 1e3);
      }
      off = true;
      continue;
    }
    off = off || e.norm() > 0.005;
    tally.drilled += 1;
    tally.errors.push_back(e.norm());
    std::printf("  %-22s x %+6.2f mm  y %+6.2f mm  |e| %5.2f mm  depth %4.1f mm\n", t.name.c_str(),
                e.horizontal * 1e3, e.vertical * 1e3, e.norm() * 1e3, hole->depth() * 1e3);
  }
  // Holes no mark claims (more than 5 cm from every mark): where the drill went instead.
  for (const concert::msg::SimHole& h : run.holes) {
    bool claimed = false;
    for (const Target& t : targets) claimed = claimed || error_of(h, t.position, t.normal).norm() <= 0.05;
    if (!claimed) {
      std::printf("  a hole at no mark: entry (%.3f, %.3f, %.3f) m in %s, depth %.1f mm\n", h.entry().x(),
                  h.entry().y(), h.entry().z(), h.wall().c_str(), h.depth() * 1e3);
      off = true;
    }
  }
  if (logs || off || s.state() != concert::msg::DRILL_SUCCEEDED) {
    std::cerr << what << ": the services' logs" << run.logs << "\n";
  }
  tally.nav += s.time_navigate();
  tally.plan += s.time_plan();
  tally.exec += s.time_execute();
  tally.drill += s.time_drill();
  tally.total += s.time_total();
  std::fflush(stdout);
}

// Scenario 3 as the paper ran it (section 6.1: "twenty-two experiments performing 60 cm wide
// horizontal patterns at different heights ranging from 0.35 m to 2.90 m"): 22 missions of one
// row each, on a fresh stack each, the rows' heights spread evenly over that range. Morphology A
// up to 2.4 m (a marker of id 0, the row 15 cm below it), C above (id 1, the row 15 cm above it:
// the marker stays within the wall). The marker stands 2.2 m in front of the robot's start,
// 0.3 m left, ahead or right in turn. Each experiment's world is a file in the temp directory.
int experiments(int runs, bool logs, const std::string& map, const concert::drill::PatternTable& patterns,
                std::pair<double, double> rows) {
  constexpr int kExperiments = 22;
  constexpr double kLowest = 0.35, kHighest = 2.90, kMorphologyC = 2.4;
  Tally all, on_a, on_c;
  int runs_a = 0, runs_c = 0;
  for (int r = 0; r < runs; ++r) {
    for (int k = 0; k < kExperiments; ++k) {
      const double row = kLowest + (kHighest - kLowest) * k / (kExperiments - 1);
      if (row < rows.first - 1e-9 || row > rows.second + 1e-9) continue;
      const bool c = row > kMorphologyC;
      const double marker = c ? row - 0.15 : row + 0.15;
      const double u = 0.3 * static_cast<double>(k % 3 - 1);  // along the wall, -y
      char name[32];
      std::snprintf(name, sizeof name, "row_%03d", static_cast<int>(std::lround(row * 100)));
      const std::filesystem::path site = std::filesystem::temp_directory_path() /
                                         ("bench_drill_experiment_" + std::to_string(::getpid()) + ".yaml");
      std::ofstream(site) << std::setprecision(6)
                          << "floor:\n  friction: 1.0\nwalls:\n"
                             "  - name: bench_wall\n    size: [0.2, 6.0, 3.2]\n    position: [2.3, 0.0, 1.6]\n"
                             "marks:\n  - {type: aruco, name: " << name
                          << ", wall: bench_wall, face: -x, at: [" << u << ", " << marker
                          << "], size: 0.1, dictionary: DICT_4X4_50, id: " << (c ? 1 : 0)
                          << ", angle: 0.0}\n";
      std::ostringstream mission;
      mission << std::setprecision(6) << "name: bench " << name << "\ndepth: 0.03\nareas:\n  - {name: "
              << name << ", marks: aruco, point: [2.2, " << -u << ", " << marker << "]}\n";
      const std::vector<Target> targets = targets_of(concert::world::load_world_file(site.string()), patterns);
      const std::string assembly =
          source(c ? "services/planner/data/morphology_c.yaml" : "services/planner/data/morphology_a.yaml");
      std::printf("experiment %d of %d (run %d): row at %.2f m, morphology %s\n", k + 1, kExperiments,
                  r + 1, row, c ? "C" : "A");
      std::fflush(stdout);
      const MissionRun run =
          run_mission(assembly, site.string(), mission.str(), std::chrono::seconds(1200), std::nullopt, map);
      std::filesystem::remove(site);
      Tally one;
      score(std::string("  ") + name, run, targets, logs, one);
      all += one;
      (c ? on_c : on_a) += one;
      (c ? runs_c : runs_a) += 1;
    }
  }
  on_a.print("experiments on morphology A (rows 0.35-2.4 m, " + std::to_string(runs_a) + " missions)", runs_a);
  on_c.print("experiments on morphology C (rows above 2.4 m, " + std::to_string(runs_c) + " missions)", runs_c);
  all.print("experiments (" + std::to_string(runs_a + runs_c) + " missions of one row)", runs_a + runs_c);
  return 0;
}

// Drilling sites nobody rehearsed (issue #51), drawn from `seed`: one mission on a fresh stack
// each, scored against the simulator's truth. A site's world is a file in the temp directory.
int generated(std::uint64_t seed, int first, int count, bool logs, const std::string& map,
              const concert::drill::PatternTable& patterns) {
  Tally all;
  int missions = 0;
  for (int k = first; k < first + count; ++k) {
    const GeneratedSite site = generate_site(seed, k, patterns);
    const std::filesystem::path world = std::filesystem::temp_directory_path() /
                                        ("bench_drill_generated_" + std::to_string(::getpid()) + ".yaml");
    std::ofstream(world) << site.world_yaml;
    const std::vector<Target> targets = targets_of(concert::world::parse_world_yaml(site.world_yaml, site.name), patterns);
    std::printf("%s of seed %llu (%d of %d): %s\n", site.name.c_str(), static_cast<unsigned long long>(seed),
                missions + 1, count, site.description.c_str());
    std::fflush(stdout);
    const std::string assembly = source(site.morphology_c ? "services/planner/data/morphology_c.yaml"
                                                          : "services/planner/data/morphology_a.yaml");
    const MissionRun run = run_mission(assembly, world.string(), site.mission_yaml, std::chrono::seconds(1800),
                                       std::nullopt, map);
    std::filesystem::remove(world);
    Tally one;
    score("  " + site.name, run, targets, logs, one);
    all += one;
    ++missions;
  }
  all.print("generated sites of seed " + std::to_string(seed) + " (" + std::to_string(missions) + " missions)",
            missions);
  return 0;
}

int bench(const std::string& which, int runs, const std::string& assembly, bool logs,
          const std::string& map, std::pair<double, double> rows, std::uint64_t seed, int first, int count) {
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
  if (which == "experiments") return experiments(runs, logs, map, patterns, rows);
  if (which == "generated") {
    int status = 0;
    for (int r = 0; r < runs && status == 0; ++r) status = generated(seed, first, count, logs, map, patterns);
    return status;
  }
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
    Tally tally;
    for (int r = 0; r < runs; ++r) {
      const MissionRun run = run_mission(assembly.empty() ? sc.assembly : assembly, site, mission,
                                         std::chrono::seconds(3600), sc.building, map);
      score(sc.name + " run " + std::to_string(r + 1), run, targets, logs, tally);
    }
    tally.print(sc.name + " (" + std::to_string(runs) + (runs == 1 ? " run)" : " runs)"), runs);
  }
  if (!known) {
    std::cerr << "bench_drill_mission: unknown scenario '" << which
              << "' (blobs, patterns, high, row, low, lowest, bim, demo, experiments, generated or all)\n";
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
  concert::cli::Cli::add_choice(app, "--scenario", which, {"blobs", "patterns", "high", "row", "low", "lowest", "bim", "demo", "experiments", "generated", "all"},
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
  std::vector<double> rows{0.0, 10.0};
  app.add_option("--rows", rows,
                 "experiments only: the rows' heights to run, MIN MAX in metres (default: all 22, "
                 "0.35-2.90 m)")
      ->expected(2)
      ->check(concert::cli::number(0.0, 10.0, false));
  std::uint64_t seed = 1;
  app.add_option("--seed", seed, "generated only: the seed the sites are drawn from")->capture_default_str();
  int count = 20;
  app.add_option("--count", count, "generated only: how many sites")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1000, true));
  int first = 1;
  app.add_option("--first", first, "generated only: the first site's number (site K is the same whatever --count is)")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1000, true));
  bool logs = false;
  app.add_flag("--logs", logs, "print the services' logs after every run (default: after a failed one, or one with a hole past 5 mm)");
  cli.on_run(app, [&] {
    if (rows[0] > rows[1]) {
      throw concert::cli::UsageError("--rows: MIN " + std::to_string(rows[0]) + " is above MAX " +
                                     std::to_string(rows[1]));
    }
    return bench(which, runs, assembly, logs, map, {rows[0], rows[1]}, seed, first, count);
  });
  return cli.run(argc, argv);
}
