#include "safety/cli.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <vector>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "concert/common/clock.hpp"
#include "concert/common/resend.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "dds/conversions.hpp"
#include "safety/safety_monitor.hpp"

namespace concert::safety {
namespace {

using namespace std::chrono_literals;

using cli::Failure;

const std::map<std::string, msg::EStopSource> kSources = {
    {"front-left", msg::ESTOP_BUTTON_FRONT_LEFT},
    {"front-right", msg::ESTOP_BUTTON_FRONT_RIGHT},
    {"rear-left", msg::ESTOP_BUTTON_REAR_LEFT},
    {"rear-right", msg::ESTOP_BUTTON_REAR_RIGHT},
    {"wireless", msg::ESTOP_WIRELESS},
    {"software", msg::ESTOP_SOFTWARE}};
/// How the safety service names `source` in its causes: the core's own name for it.
std::string service_name(msg::EStopSource source) {
  const auto core = safety::dds::to_core(source);
  return core ? std::string(to_string(*core)) : "unknown";
}

/// What the operator verbs take.
struct Options {
  cli::DdsOptions dds;
  std::string source;  ///< estop: the input (default software); reset: who asks
  std::string reason;
  bool release = false;
};

nlohmann::ordered_json json_of(const msg::SafetyState& s) {
  return {{"mode", s.mode() == msg::SAFETY_RUNNING ? "RUNNING" : "STOPPED"},
          {"causes", s.causes()}};
}

std::string describe(const msg::SafetyState& s) {
  if (s.mode() == msg::SAFETY_RUNNING) return "RUNNING";
  std::string text = "STOPPED (reset required)";
  for (const auto& c : s.causes()) text += "\n  " + c;
  return text;
}

/// Waits for a SafetyState sample satisfying `accept`, or nullopt at the deadline.
template <class F>
std::optional<msg::SafetyState> wait_state(concert::dds::Reader<msg::SafetyState>& reader,
                                           std::chrono::milliseconds limit, F accept) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = reader.wait(50ms); s && accept(*s)) return s;
  }
  return std::nullopt;
}

int status(const Options& o, concert::dds::Participant& p, std::ostream& out) {
  concert::dds::Reader<msg::SafetyState> states(p, concert::dds::topics::safety_state);
  const auto s = wait_state(states, o.dds.timeout(), [](const auto&) { return true; });
  if (!s)
    throw Failure("no safety state on domain " + std::to_string(p.domain_id()) +
                  " (is concert_safety running?)");
  if (o.dds.json) {
    out << json_of(*s).dump() << "\n";
  } else {
    out << "safety: " << describe(*s) << "\n";
  }
  return 0;
}

/// Waits until `writer` has matched a reader of the safety service's own participant (known
/// from its ServiceStatus heartbeat): other readers of the topic (the GUI's, a recorder's) may
/// match and acknowledge first, and a latched input written before the safety service matched
/// would be lost with this short-lived writer.
bool wait_for_safety_reader(concert::dds::Participant& p, const concert::dds::Writer<msg::EStopInput>& writer,
                            std::chrono::milliseconds timeout) {
  std::mutex mutex;
  std::optional<eprosima::fastrtps::rtps::GuidPrefix_t> safety;
  concert::dds::Reader<msg::ServiceStatus> statuses(
      p, concert::dds::topics::status, [&](const msg::ServiceStatus& s, const eprosima::fastdds::dds::SampleInfo& info) {
        if (s.service() != "safety") return;
        std::lock_guard lock(mutex);
        safety = info.sample_identity.writer_guid().guidPrefix;
      });
  return concert::dds::detail::wait_until(
      [&] {
        std::lock_guard lock(mutex);
        return safety && writer.matched_participant(*safety);
      },
      timeout);
}

int estop(const Options& o, concert::dds::Participant& p, std::ostream& out) {
  const std::string name = o.source.empty() ? "software" : o.source;
  const auto source = kSources.find(name);
  // Read before writing: the answer to an engaged input is a STOPPED state naming it.
  concert::dds::Reader<msg::SafetyState> states(p, concert::dds::topics::safety_state);
  concert::dds::Writer<msg::EStopInput> writer(p, concert::dds::topics::estop, concert::dds::TrackMatches::kYes);
  if (!wait_for_safety_reader(p, writer, o.dds.timeout())) {
    throw Failure("no safety service on domain " + std::to_string(p.domain_id()) +
                  " read the e-stop input");
  }
  msg::EStopInput input;
  input.source(source->second);
  input.engaged(!o.release);
  input.stamp_ns(now_ns());
  input.reason(o.reason.empty() ? "concert safety estop" : o.reason);
  writer.write(input);
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(o.dds.timeout()).count();
  if (writer.get()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
          static_cast<int32_t>(ns / 1'000'000'000), static_cast<uint32_t>(ns % 1'000'000'000))) !=
      eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    throw Failure("the safety service did not acknowledge the e-stop input");
  }
  // The safety service's reader is among those that acknowledged (wait_for_safety_reader); an
  // engaged input counts once the service also says it stopped for it.
  if (!o.release) {
    // The service's cause names the input ("estop: button front left engaged (reason)"); the
    // reason is left out of the match: a cause already latched keeps its first reason.
    const std::string cause = "estop: " + service_name(source->second) + " engaged";
    const auto stopped = wait_state(states, o.dds.timeout(), [&](const msg::SafetyState& st) {
      if (st.mode() != msg::SAFETY_STOPPED) return false;
      for (const auto& c : st.causes()) {
        if (c.rfind(cause, 0) == 0) return true;
      }
      return false;
    });
    if (!stopped) {
      throw Failure("the safety service did not report a stop for the e-stop input '" + name +
                    "' within " + std::to_string(o.dds.timeout_s) + " s");
    }
  }
  if (o.dds.json) {
    out << nlohmann::ordered_json{{"source", name}, {"engaged", !o.release}}.dump() << "\n";
  } else {
    out << "safety: e-stop " << name << (o.release ? " released" : " engaged") << "\n";
  }
  return 0;
}

int reset(const Options& o, concert::dds::Participant& p, std::ostream& out, std::ostream& err) {
  concert::dds::Reader<msg::SafetyState> states(p, concert::dds::topics::safety_state);
  concert::dds::Reader<msg::ServiceStatus> statuses(p, concert::dds::topics::status);
  concert::dds::Writer<msg::SafetyReset> writer(p, concert::dds::topics::safety_reset);
  if (!writer.wait_for_readers(1, o.dds.timeout())) {
    throw Failure("no safety service on domain " + std::to_string(p.domain_id()) + " to reset");
  }
  const int64_t sent = now_ns();
  msg::SafetyReset request;
  request.request_id(static_cast<uint32_t>(sent / 1000 % 4'000'000'000));
  request.stamp_ns(sent);
  request.source(o.source.empty() ? "concert safety reset@" + concert::dds::host_name() : o.source);
  request.reason(o.reason);
  // Heartbeats repeat the service's last message with a fresh stamp, so a refusal is
  // recognised by naming this request's source, not by its time.
  const std::string refusal = "reset by " + request.source() + " refused";
  // The service answers a reset with a state publication stamped after it, but it also
  // publishes states for other reasons (an input just released, a heartbeat): a STOPPED state
  // alone is no answer. Success is a RUNNING state; refusal is the service's status naming
  // the reason. The reset is written again every second until either is heard (the reader
  // matched first may be another tool's; the service takes this request once).
  std::string why = "reset refused (no reason received)";
  std::optional<msg::SafetyState> last;
  bool running = false;
  const auto answered = [&](std::chrono::steady_clock::time_point until) {
    while (std::chrono::steady_clock::now() < until) {
      while (auto st = states.take()) {
        if (st->stamp_ns() < sent) continue;
        last = *st;
        if (st->mode() == msg::SAFETY_RUNNING) return running = true;
      }
      const auto status = statuses.wait(20ms);
      if (status && status->service() == "safety" && status->stamp_ns() >= sent &&
          status->message().find(refusal) != std::string::npos) {
        why = status->message();
        return true;
      }
    }
    return false;
  };
  resend_until_answered([&] { writer.write(request); }, answered,
                        std::chrono::steady_clock::now() + o.dds.timeout());
  if (running) {
    out << (o.dds.json ? json_of(*last).dump() : "safety: " + describe(*last)) << "\n";
    return 0;
  }
  if (last) {
    out << (o.dds.json ? json_of(*last).dump() : "safety: " + describe(*last)) << "\n";
  } else if (why.find(refusal) == std::string::npos) {
    throw Failure("the safety service did not answer the reset");
  }
  err << "concert safety reset: " << why << "\n";
  return 1;
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& safety = concert.group(concert.app(), "safety",
                                   "the safety layer: state, e-stop inputs, reset a latched stop");
  auto add = [&concert, &safety](const std::string& name, const std::string& what, auto body) {
    auto o = std::make_shared<Options>();
    CLI::App& verb = concert.verb(safety, name, what, [&concert, o, body] {
      concert::dds::Participant participant({.name = "concert-safety-cli", .domain_id = o->dds.domain_id()});
      return body(*o, participant, concert.out(), concert.err());
    });
    concert.add_dds_options(verb, o->dds, 5.0, "how long to wait for the safety service");
    return std::make_pair(&verb, o);
  };
  add("status", "the live safety state: RUNNING, or STOPPED with its causes",
      [](const Options& o, concert::dds::Participant& p, std::ostream& out, std::ostream&) {
        return status(o, p, out);
      });
  auto [estop_verb, estop_options] =
      add("estop", "engage (or release) an e-stop input",
          [](const Options& o, concert::dds::Participant& p, std::ostream& out, std::ostream&) {
            return estop(o, p, out);
          });
  std::vector<std::string> sources;
  for (const auto& [name, value] : kSources) sources.push_back(name);
  cli::Cli::add_choice(*estop_verb, "--source", estop_options->source, sources,
                       "the e-stop input (default: software)");
  estop_verb->add_flag("--release", estop_options->release,
                       "release the input instead of engaging it");
  estop_verb->add_option("--reason", estop_options->reason, "why (shown in the stop causes)")
      ->type_name("TEXT");
  auto [reset_verb, reset_options] = add(
      "reset", "ask the safety service to reset a latched stop; prints the resulting state", reset);
  reset_verb
      ->add_option("--source", reset_options->source,
                   "who asks (default: concert safety reset@HOST)")
      ->type_name("NAME");
  reset_verb->add_option("--reason", reset_options->reason, "why")->type_name("TEXT");
}

}  // namespace concert::safety
