// concert_surface_finish: sanding and spraying of a wall area (paper sections 5.7, 6.2).
// Reconfigures on every RobotModel (the arm's spraying or sanding tool, the predetermined areas
// at the working distance), measures the wall from the lidars' planar scan, and runs the
// serpentine as a joint trajectory through the robot service, measuring the coverage.
//   concert_surface_finish [--rate HZ] [--out-dir DIR] [--speed M_S]
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM (a running path is stopped, the arm held).
#include <atomic>
#include <iostream>
#include <string>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/finish_node.hpp"

namespace {

int run(const concert::surface_finish::dds::NodeParams& params) {
  using namespace concert;
  const std::atomic<bool>& stop = cli::stop_on_signals();
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "surface_finish"});
  surface_finish::dds::FinishNode node(participant, params, std::cerr);
  std::cerr << "concert_surface_finish: domain " << participant.domain_id() << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_surface_finish", "Sanding and spraying of a wall area.", std::cout, std::cerr);
  concert::surface_finish::dds::NodeParams params;
  auto& app = cli.app();
  app.add_option("--rate", params.rate, "control rate [Hz]")->check(concert::cli::number(5.0, 500.0));
  app.add_option("--out-dir", params.out_dir, "where each run's report (JSON) and coverage map (PNG) go")
      ->type_name("DIR");
  app.add_option("--speed", params.path.speed, "default TCP speed along the strokes [m/s]")
      ->check(concert::cli::number(0.01, 1.0));
  cli.on_run(app, [&params] { return run(params); });
  return cli.run(argc, argv);
}
