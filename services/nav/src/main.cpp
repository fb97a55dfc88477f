// concert_nav: navigation of the mobile base in the building (paper section 5.3). Reconfigures
// on every RobotModel (vehicle kinematics, footprint, sensors), localises in the storey map with
// the lidars, plans and drives to NavGoals (map poses, or in front of a BIM wall).
//   concert_nav [--params FILE] [--ifc FILE --storey NAME [--resolution M] [--margin M]] [--map
//   MAP.yaml]
//               [--initial-pose X Y THETA]
// The map comes from an IFC file (imported with web-ifc at start: walls, doors, wall goals) or a
// nav2 map_server file (pose goals only). Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <chrono>
#include <iostream>
#include <string>

#include "concert/common/memory.hpp"
#include "concert/bim/model.hpp"
#include "concert/bim/storey_map.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/nav_node.hpp"
#include "nav/navigator.hpp"

namespace {

struct Options {
  std::string params;
  std::string ifc;
  std::string storey;
  double resolution = 0.05;
  double margin = 3.0;
  std::string map;
  std::vector<double> initial_pose;
  uint64_t seed = 1;
};

int run(const Options& o) {
  using namespace concert;
  nav::NavParams params;
  if (!o.params.empty()) params = nav::load_params(o.params);
  if (!o.ifc.empty() && !o.map.empty()) throw cli::UsageError("give --ifc or --map, not both");
  if (!o.ifc.empty() && o.storey.empty()) throw cli::UsageError("--ifc needs --storey NAME");
  nav::Navigator navigator(params, o.seed);
  std::string source;
  if (!o.ifc.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    auto bim = std::make_shared<const bim::BimModel>(bim::load_ifc(o.ifc));
    const bim::Storey& storey = bim->storey(o.storey);
    bim::SliceParams slice;
    slice.resolution = o.resolution;
    slice.margin = o.margin;
    auto grid = bim::storey_map(*bim, storey, slice);
    std::cerr << "concert_nav: " << o.ifc << " storey '" << storey.name << "': " << grid.width
              << " x " << grid.height << " cells at " << grid.resolution << " m in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()
              << " s" << std::endl;
    navigator.set_map(std::move(grid), storey.name, bim);
    source = o.ifc;
  } else if (!o.map.empty()) {
    navigator.set_map(bim::load_map(o.map), o.map);
    source = o.map;
  }
  if (!o.initial_pose.empty()) {
    navigator.set_initial_pose({o.initial_pose[0], o.initial_pose[1], o.initial_pose[2]}, 0.0, 0.0);
  }
  const std::atomic<bool>& stop = cli::stop_on_signals();
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "nav"});
  nav::dds::NavNode node(participant, navigator, source, std::cerr);
  std::cerr << "concert_nav: domain " << participant.domain_id()
            << (navigator.has_map() ? ", map '" + navigator.map_name() + "'"
                                    : ", no map (goals refused until one is given)")
            << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_nav",
                        "Navigation of the mobile base in the building (BIM map, lidars).",
                        std::cout, std::cerr);
  Options o;
  auto& app = cli.app();
  app.add_option("--params", o.params, "parameters file (config/nav.yaml lists every key)")
      ->type_name("FILE");
  app.add_option("--ifc", o.ifc, "the building's IFC file (walls, doors; wall goals)")
      ->type_name("FILE");
  app.add_option("--storey", o.storey, "with --ifc: the storey to navigate")->type_name("NAME");
  app.add_option("--resolution", o.resolution, "with --ifc: map cell size [m]")
      ->check(concert::cli::number(0.01, 1.0));
  app.add_option("--margin", o.margin,
                 "with --ifc: free border mapped around the building [m] (room to arrive)")
      ->check(concert::cli::number(0.0, 50.0));
  app.add_option("--map", o.map, "a nav2 map_server map (map.yaml + image)")->type_name("FILE");
  app.add_option("--initial-pose", o.initial_pose, "the robot's pose in the map at start")
      ->expected(3)
      ->type_name("X Y THETA")
      ->check(concert::cli::real());
  app.add_option("--seed", o.seed, "seed of the localiser's random numbers");
  cli.on_run(app, [&o] { return run(o); });
  return cli.run(argc, argv);
}
