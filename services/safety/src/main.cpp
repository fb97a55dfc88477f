// concert_safety: the safety layer. Watches the e-stop inputs, the liveliness of the robot and
// task services and the joint limits; publishes concert/safety/state (STOPPED, latched until
// every input is released and a SafetyReset arrives).
//   concert_safety [--params FILE]
// Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <csignal>
#include <iostream>
#include <string>

#include "concert/dds/participant.hpp"
#include "dds/safety_node.hpp"
#include "safety/params.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop = true; }

constexpr const char* kUsage = "usage: concert_safety [--params FILE]";

}  // namespace

int main(int argc, char** argv) {
  using namespace concert;
  try {
    safety::Params params;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--params") {
        if (i + 1 >= argc) throw std::runtime_error("option --params needs a value");
        params = safety::load_params(argv[++i]);
      } else if (arg == "--help" || arg == "-h") {
        std::cout << kUsage << "\n";
        return 0;
      } else {
        throw std::runtime_error("unknown argument '" + arg + "'");
      }
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    safety::dds::use_interprocess_delivery_only();
    concert::dds::Participant participant(concert::dds::ParticipantOptions{.name = "safety"});
    safety::dds::SafetyNode node(participant, params, std::cerr);
    std::string watched = params.robot_service;
    for (const auto& s : params.task_services) watched += ", " + s;
    std::cerr << "concert_safety: domain " << participant.domain_id() << ", watching " << watched
              << " (silent > " << params.liveliness_timeout.count() << " ms -> stop)" << std::endl;
    node.spin(g_stop);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "concert_safety: " << e.what() << "\n" << kUsage << "\n";
    return 1;
  }
}
