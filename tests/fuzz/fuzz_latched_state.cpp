// The safety service's latched-state file (services/safety: the stop, its causes, the e-stop
// inputs engaged and the services watched, restored when the service restarts). The file lies in
// the run folder, may be left half-written by a crash of another tool or edited by hand; what the
// service restores from it decides whether the robot may move. A state that parses must write
// back to the same state, and a monitor restored from it must keep a stop latched. Documented
// failure: config::ConfigError.
//
// Seeds: the states the service writes (running, stopped with causes and engaged inputs, many
// watched services).
#include <chrono>
#include <string>

#include "concert/config/config.hpp"
#include "fuzz.hpp"
#include "safety/latched_state.hpp"
#include "safety/safety_monitor.hpp"

namespace {

using namespace concert;

safety::LatchedState stopped_state() {
  safety::LatchedState s;
  s.mode = safety::Mode::kStopped;
  s.causes = {"estop: wireless engaged (operator)", "liveliness: drill@manip-pc silent for 1.2 s"};
  s.cause_keys = {"estop:wireless", "silent:drill@manip-pc"};
  s.engaged = {safety::EStopSource::kWireless, safety::EStopSource::kSoftware};
  s.watched = {{"drill@manip-pc", "1.f3.0.0.1"}, {"robot@rt-pc", ""}};
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  safety::LatchedState state;
  try {
    state = safety::parse_latched_state(std::string(fuzz::text_of(data, size)), "latched.yaml");
  } catch (const config::ConfigError&) {
    return 0;
  }
  const std::string written = safety::to_yaml(state);
  safety::LatchedState again;
  try {
    again = safety::parse_latched_state(written, "written.yaml");
  } catch (const config::ConfigError& e) {
    fuzz::check_failed(__FILE__, __LINE__, "parse(to_yaml(state))",
                       std::string("the service cannot read back what it wrote: ") + e.what());
  }
  CONCERT_FUZZ_CHECK(again == state, "a state written and read back is another state");

  const auto now = safety::TimePoint{} + std::chrono::seconds(100);
  safety::SafetyMonitor monitor(safety::Params{}, now);
  monitor.restore(state, now);
  if (state.mode == safety::Mode::kStopped || !state.engaged.empty()) {
    CONCERT_FUZZ_CHECK(monitor.status().mode == safety::Mode::kStopped,
                       "a restored stop or engaged e-stop input left the robot RUNNING");
    CONCERT_FUZZ_CHECK(!monitor.reset("fuzz", now).accepted || state.engaged.empty(),
                       "a reset was accepted with an e-stop input engaged");
  }
  return 0;
}

void concert::fuzz::write_seeds(SeedWriter& seeds) {
  seeds.add("running.yaml", safety::to_yaml(safety::LatchedState{}));
  seeds.add("stopped.yaml", safety::to_yaml(stopped_state()));
  safety::LatchedState many = stopped_state();
  for (int i = 0; i < 20; ++i) many.watched["svc" + std::to_string(i) + "@host"] = std::to_string(i);
  seeds.add("many.yaml", safety::to_yaml(many));
  seeds.add_tokens(kYamlTokens);
}
