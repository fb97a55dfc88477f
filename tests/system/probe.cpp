// concert_system_probe: a stand-in task service for system tests. It beats on the status
// topic as SERVICE (like every service), reconfigures to each RobotModel it receives (prints
// "model <version> <content_hash> <joints>" and reports ready at that version), and prints
// every change of the safety state ("safety RUNNING" / "safety STOPPED: cause; cause").
//   concert_system_probe --service NAME     Domain: CONCERT_DOMAIN_ID. Stops on SIGINT/SIGTERM.
#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <string>

#include "concert/cli/cli.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

int run(const std::string& service) {
  namespace dds = concert::dds;
  namespace msg = concert::msg;
  {
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    dds::Participant participant({.name = service});
    dds::Reader<msg::RobotModel> models(participant, dds::topics::robot_model);
    dds::Reader<msg::SafetyState> safety(participant, dds::topics::safety_state);
    dds::StatusReporter status(participant, service);
    status.report(msg::SERVICE_STARTING, 0, "waiting for a robot model");
    std::cout << "probe " << service << "@" << dds::host_name() << " started" << std::endl;
    std::string last_safety;
    while (!g_stop) {
      if (auto m = models.wait(std::chrono::milliseconds(50))) {
        std::cout << "model " << m->version() << " " << m->content_hash() << " "
                  << m->joints().size() << std::endl;
        status.report(msg::SERVICE_READY, m->version(), "ready");
      }
      while (auto s = safety.take()) {
        std::string text = s->mode() == msg::SAFETY_STOPPED ? "safety STOPPED" : "safety RUNNING";
        for (std::size_t i = 0; i < s->causes().size(); ++i)
          text += (i == 0 ? ": " : "; ") + s->causes()[i];
        if (text != last_safety) std::cout << text << std::endl;
        last_safety = text;
      }
    }
    return 0;
  }
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli probe("concert_system_probe", "A stand-in task service for system tests.",
                          std::cout, std::cerr);
  std::string service;
  probe.app()
      .add_option("--service", service, "the service name it reports as")
      ->type_name("NAME")
      ->required();
  probe.on_run(probe.app(), [&service] { return run(service); });
  return probe.run(argc, argv);
}
