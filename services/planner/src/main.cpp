// concert_planner: whole-body planning for drilling (paper section 5.4.2). Reconfigures on
// every RobotModel, plans PlanRequests (NSPG + RRT-Connect) and executes them through the
// robot service.
//   concert_planner [--params FILE] [--world FILE] [--map world|sensors|both]
// The latched world topic (concert/world/world) replaces the map whenever it changes; with
// environment_source: sensors (or both) the map comes from the robot's lidars (README, "Map from
// the sensors").
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <iostream>
#include <string>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/planner_node.hpp"
#include "concert/world/world.hpp"
#include "planner/config.hpp"

namespace {

struct Options {
  std::string params;
  std::string world;
  std::string map;  // environment_source over the parameters file's
};

int run(const Options& options) {
  using namespace concert;
  planner::Params params;
  planner::World world;
  if (!options.params.empty()) params = planner::load_params(options.params);
  if (!options.map.empty()) params.environment_source = options.map;
  // The world file (libs/world format) is the map until the world topic brings another.
  if (!options.world.empty()) {
    world = planner::dds::to_planner_world(world::load_world_file(options.world));
  }
  const std::atomic<bool>& stop = concert::cli::stop_on_signals();
  planner::Planner planner(params);
  planner::Environment env(params.octomap_resolution);
  env.add_world(world);
  planner.set_environment(env);
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "planner"});
  planner::dds::PlannerNode node(participant, planner, {}, std::cerr);
  std::cerr << "concert_planner: domain " << participant.domain_id() << ", map "
            << env.occupied_cells() << " occupied cells"
            << (options.world.empty() ? "" : " from " + options.world) << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_planner", "Whole-body planning for drilling (NSPG + RRT-Connect).",
                        std::cout, std::cerr);
  Options options;
  cli.app()
      .add_option("--params", options.params,
                  "parameters file (config/planner.yaml lists every key)")
      ->type_name("FILE");
  cli.app().add_option("--world", options.world, "the world (walls, obstacles)")->type_name("FILE");
  concert::cli::Cli::add_choice(cli.app(), "--map", options.map, {"world", "sensors", "both"},
                                "what the map is built from (the parameters' environment_source; default world)");
  cli.on_run(cli.app(), [&options] { return run(options); });
  return cli.run(argc, argv);
}
