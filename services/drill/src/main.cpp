// concert_drill: drilling missions (paper section 5.4). Reconfigures on every RobotModel (the
// drill end-effector and its camera), runs one mission at a time as a behaviour tree: locate
// the areas, navigate, plan and execute the approach, detect the marks, drill each hole with
// Cartesian impedance and visual servoing, retract.
//   concert_drill [--params FILE] [--patterns FILE] [--rate HZ] [--unseen-frames DIR]
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM (a running mission is aborted, the arm held).
#include <atomic>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>

#include "concert/common/memory.hpp"
#include "concert/cli/cli.hpp"
#include "concert/cli/stop_signals.hpp"
#include "concert/dds/participant.hpp"
#include "dds/drill_node.hpp"

namespace {

struct Options {
  std::string params = CONCERT_DRILL_PARAMS;
  std::string patterns = CONCERT_DRILL_PATTERNS;
  double rate = 50.0;
  std::string unseen_frames;
};

int run(const Options& o) {
  using namespace concert;
  drill::dds::NodeParams params;
  params.patterns = o.patterns;
  params.rate = o.rate;
  params.unseen_frames_dir = o.unseen_frames;
  // Read now, so that a bad file stops the service naming the key and line.
  params.tuning = drill::load_params(o.params);
  if (!o.unseen_frames.empty()) {
    // Made now, so that a directory that cannot be made stops the service with the reason.
    std::error_code error;
    std::filesystem::create_directories(o.unseen_frames, error);
    if (error || !std::filesystem::is_directory(o.unseen_frames))
      throw std::runtime_error("--unseen-frames: cannot make the directory '" + o.unseen_frames +
                               "'" + (error ? ": " + error.message() : std::string()));
  }
  // The table is read now so that a bad file stops the service with the reason.
  (void)drill::load_patterns(o.patterns);
  const std::atomic<bool>& stop = cli::stop_on_signals();
  concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "drill"});
  drill::dds::DrillNode node(participant, params, std::cerr);
  std::cerr << "concert_drill: domain " << participant.domain_id() << ", parameters " << o.params
            << ", hole patterns " << o.patterns << std::endl;
  node.spin(stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  concert::fix_malloc_thresholds();  // a heap that does not grow with every hot swap
  concert::cli::Cli cli("concert_drill",
                        "Drilling missions: marks -> areas -> approach -> closed-loop drilling.",
                        std::cout, std::cerr);
  Options o;
  auto& app = cli.app();
  app.add_option("--params", o.params, "tuning (config/drill.yaml: every key with its default)")
      ->type_name("FILE");
  app.add_option("--patterns", o.patterns, "ArUco hole-pattern table (config/patterns.yaml)")
      ->type_name("FILE");
  app.add_option("--rate", o.rate, "control rate [Hz]")->check(concert::cli::number(5.0, 500.0));
  app.add_option("--unseen-frames", o.unseen_frames,
                 "write each camera view in which a looked-for mark was not found to DIR (PNG, "
                 "the mark's expected pixel crossed)")
      ->type_name("DIR");
  cli.on_run(app, [&o] { return run(o); });
  return cli.run(argc, argv);
}
