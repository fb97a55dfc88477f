// concert_safety: the safety layer. Watches the e-stop inputs, the liveliness of the robot and
// task services and the joint limits; publishes concert/safety/state (STOPPED, latched until
// every input is released and a SafetyReset arrives).
//   concert_safety [--params FILE] [--state FILE]
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <iostream>
#include <string>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/common/priority.hpp"
#include "concert/dds/participant.hpp"
#include "dds/safety_node.hpp"
#include "safety/params.hpp"

namespace {

int run(const std::string& params_file, const std::string& state_file) {
  using namespace concert;
  safety::Params params;
  if (!params_file.empty()) params = safety::load_params(params_file);
  // Before any thread exists: the DDS threads created below inherit the value.
  if (const auto nice = concert::set_thread_nice(params.nice); !nice.applied) {
    std::cerr << "concert_safety: running at nice " << nice.now << ", not " << params.nice << " ("
              << nice.error << "; CAP_SYS_NICE lets it): on a loaded PC its checks may wait"
              << std::endl;
  }
  const std::atomic<bool>& stop = concert::cli::stop_on_signals();
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "safety"});
  safety::dds::SafetyNode node(participant, params, std::cerr, state_file);
  std::string watched = params.robot_service;
  for (const auto& s : params.task_services) watched += ", " + s;
  std::cerr << "concert_safety: domain " << participant.domain_id() << ", watching " << watched
            << " (silent > " << params.liveliness_timeout.count() << " ms -> stop)" << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli(
      "concert_safety",
      "The safety layer: e-stop inputs, liveliness of the services, joint limits.", std::cout,
      std::cerr);
  std::string params;
  std::string state;
  cli.app()
      .add_option("--params", params, "parameters file (config/safety.yaml lists every key)")
      ->type_name("FILE");
  cli.app()
      .add_option("--state", state,
                  "keep the latched state (stop, causes, e-stop inputs, watched services) in "
                  "FILE: restored at start, rewritten on every change")
      ->type_name("FILE");
  cli.on_run(cli.app(), [&params, &state] { return run(params, state); });
  return cli.run(argc, argv);
}
