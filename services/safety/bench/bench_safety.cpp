// bench_safety: (1) limits watchdog cost per joint sample (core, 14-joint model, as the drill
// robot), (2) e-stop reaction over DDS: EStopInput written -> SafetyState STOPPED received, and
// reset -> RUNNING, through a real SafetyNode in another participant (shared-memory/UDP
// loopback, as between two processes). Median and p95 over the repetitions.
//   bench_safety [REPETITIONS]      Domain: CONCERT_DOMAIN_ID.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "concert/cli/cli.hpp"
#include "concert/dds/endpoint.hpp"
#include "dds/safety_node.hpp"
#include "safety/safety_monitor.hpp"

namespace {

namespace dds = concert::dds;
namespace msg = concert::msg;
namespace safety = concert::safety;
using namespace std::chrono_literals;
using Ms = std::chrono::duration<double, std::milli>;

void report(const char* what, std::vector<double> v, const char* unit) {
  if (v.empty()) {
    std::printf("%-44s no samples\n", what);
    return;
  }
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) {
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
  };
  std::printf("%-44s median %8.3f %s   p95 %8.3f %s   max %8.3f %s   (n=%zu)\n", what, at(0.5),
              unit, at(0.95), unit, v.back(), unit, v.size());
}

void bench_core() {
  safety::SafetyMonitor monitor(safety::Params{}, safety::Clock::now());
  std::vector<concert::model::JointLimits> joints;
  safety::JointSample sample;
  sample.model_version = 1;
  for (int i = 0; i < 14; ++i) {
    joints.push_back({"joint_" + std::to_string(i), "A", -2.0, 2.0, 3.0, 100.0, 60.0});
    sample.name.push_back("joint_" + std::to_string(i));
    sample.position.push_back(0.1 * i - 0.7);
    sample.velocity.push_back(0.5);
    sample.effort.push_back(20.0);
  }
  monitor.set_model(1, concert::model::LimitsTable(joints, "bench"));
  std::vector<double> per_sample;
  for (int round = 0; round < 20; ++round) {
    constexpr int kSamples = 10'000;
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kSamples; ++i) monitor.on_joint_state(sample, std::chrono::steady_clock::now());
    per_sample.push_back(
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
        kSamples);
  }
  if (monitor.status().mode != safety::Mode::kRunning) std::printf("unexpected stop\n");
  report("limits check, 14 joints (per sample)", per_sample, "ns");
}

template <class F>
bool wait_mode(dds::Reader<msg::SafetyState>& states, msg::SafetyMode mode, F&& on_time) {
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = states.wait(100ms); s && s->mode() == mode) {
      on_time();
      return true;
    }
  }
  return false;
}

void bench_dds(int repetitions) {
  dds::Participant service_side({.name = "bench_safety_service"});
  std::ostringstream log;
  safety::dds::SafetyNode node(service_side, safety::Params{}, log);
  std::atomic<bool> stop{false};
  std::thread spinner([&] { node.spin(stop); });

  dds::Participant operator_side({.name = "bench_safety_operator"});
  dds::Reader<msg::SafetyState> states(operator_side, dds::topics::safety_state);
  dds::Writer<msg::EStopInput> inputs(operator_side, dds::topics::estop);
  dds::Writer<msg::SafetyReset> resets(operator_side, dds::topics::safety_reset);
  if (!inputs.wait_for_readers(1, 10s) || !resets.wait_for_readers(1, 10s) ||
      !wait_mode(states, msg::SAFETY_RUNNING, [] {})) {
    std::printf("e-stop over DDS: the safety node was not matched\n");
  } else {
    std::vector<double> stop_ms, reset_ms;
    msg::EStopInput in;
    in.source(msg::ESTOP_WIRELESS);
    msg::SafetyReset reset;
    reset.source("bench");
    for (int i = 0; i < repetitions; ++i) {
      in.engaged(true);
      auto t0 = std::chrono::steady_clock::now();
      inputs.write(in);
      if (!wait_mode(states, msg::SAFETY_STOPPED,
                     [&] { stop_ms.push_back(Ms(std::chrono::steady_clock::now() - t0).count()); }))
        break;
      in.engaged(false);
      inputs.write(in);
      std::this_thread::sleep_for(5ms);
      reset.request_id(static_cast<uint32_t>(i));
      t0 = std::chrono::steady_clock::now();
      resets.write(reset);
      if (!wait_mode(states, msg::SAFETY_RUNNING, [&] {
            reset_ms.push_back(Ms(std::chrono::steady_clock::now() - t0).count());
          }))
        break;
    }
    report("e-stop engaged -> STOPPED received (DDS)", stop_ms, "ms");
    report("reset -> RUNNING received (DDS)", reset_ms, "ms");
  }
  stop = true;
  spinner.join();
}

}  // namespace

int main(int argc, char** argv) {
  concert::cli::Cli cli(
      "bench_safety",
      "The limits watchdog's cost per joint sample, and e-stop reaction over DDS "
      "through a real SafetyNode in another participant. Domain: CONCERT_DOMAIN_ID.",
      std::cout, std::cerr);
  int repetitions = 200;
  cli.app()
      .add_option("REPETITIONS", repetitions, "e-stop / reset cycles measured over DDS")
      ->capture_default_str()
      ->check(concert::cli::number(1, 1e6, true));
  cli.on_run(cli.app(), [&repetitions] {
    bench_core();
    bench_dds(repetitions);
    return 0;
  });
  return cli.run(argc, argv);
}
