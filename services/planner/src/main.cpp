// concert_planner: whole-body planning for drilling (paper section 5.4.2). Reconfigures on
// every RobotModel, plans PlanRequests (NSPG + RRT-Connect) and executes them through the
// robot service.
//   concert_planner [--params FILE] [--world FILE]
// The latched world topic (concert/world/world) replaces the map whenever it changes.
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <csignal>
#include <iostream>
#include <string>

#include "concert/dds/participant.hpp"
#include "dds/planner_node.hpp"
#include "concert/world/world.hpp"
#include "planner/config.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop = true; }

constexpr const char* kUsage = "usage: concert_planner [--params FILE] [--world FILE]";

}  // namespace

int main(int argc, char** argv) {
  using namespace concert;
  try {
    planner::Params params;
    planner::World world;
    std::string world_file;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--params" || arg == "--world") {
        if (i + 1 >= argc) throw std::runtime_error("option " + arg + " needs a value");
        if (arg == "--params") {
          params = planner::load_params(argv[++i]);
        } else {
          world_file = argv[++i];
        }
      } else if (arg == "--help" || arg == "-h") {
        std::cout << kUsage << "\n";
        return 0;
      } else {
        throw std::runtime_error("unknown argument '" + arg + "'");
      }
    }
    // The world file (libs/world format) is the map until the world topic brings another.
    if (!world_file.empty()) world = planner::dds::to_planner_world(world::load_world_file(world_file));
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    planner::Planner planner(params);
    planner::Environment env(params.octomap_resolution);
    env.add_world(world);
    planner.set_environment(env);
    concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "planner"});
    planner::dds::PlannerNode node(participant, planner, {}, std::cerr);
    std::cerr << "concert_planner: domain " << participant.domain_id() << ", map " << env.occupied_cells() << " occupied cells"
              << (world_file.empty() ? "" : " from " + world_file) << std::endl;
    node.spin(g_stop);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "concert_planner: " << e.what() << "\n" << kUsage << "\n";
    return 1;
  }
}
