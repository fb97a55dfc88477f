// concert_collab: collaborative transportation (paper sections 5.5-5.6). Reconfigures on every
// RobotModel (the arm and its gripper), runs the Fig. 12 state machine on the commands of
// concert/collab/command (voice: `concert collab listen`, text: `concert collab say`, the GUI:
// `concert collab mode`), drives the robot service for each state, runs the follow-me MPC.
//   concert_collab [--rate HZ] [--lift M] [--object-mass KG]
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM (the base is stopped).
#include <atomic>
#include <iostream>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/collab_node.hpp"

namespace {

int run(const concert::collab::dds::NodeParams& params) {
  using namespace concert;
  const std::atomic<bool>& stop = cli::stop_on_signals();
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "collab"});
  collab::dds::CollabNode node(participant, params, std::cerr);
  std::cerr << "concert_collab: domain " << participant.domain_id() << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_collab", "Collaborative transportation: voice-commanded modes, follow-me MPC.",
                        std::cout, std::cerr);
  concert::collab::dds::NodeParams params;
  auto& app = cli.app();
  app.add_option("--rate", params.rate, "control rate [Hz]")->check(concert::cli::number(5.0, 200.0));
  app.add_option("--lift", params.lift_height, "lift/place travel [m]")->check(concert::cli::number(0.01, 0.5));
  app.add_option("--object-mass", params.object_mass,
                 "the carried object's mass [kg]: the robot compensates its weight from lift until open")
      ->check(concert::cli::number(0.0, 100.0));
  cli.on_run(app, [&params] { return run(params); });
  return cli.run(argc, argv);
}
