#include "safety/cli.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <stdexcept>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"

namespace concert::safety {
namespace {

using namespace std::chrono_literals;

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const std::map<std::string, msg::EStopSource> kSources = {
    {"front-left", msg::ESTOP_BUTTON_FRONT_LEFT},
    {"front-right", msg::ESTOP_BUTTON_FRONT_RIGHT},
    {"rear-left", msg::ESTOP_BUTTON_REAR_LEFT},
    {"rear-right", msg::ESTOP_BUTTON_REAR_RIGHT},
    {"wireless", msg::ESTOP_WIRELESS},
    {"software", msg::ESTOP_SOFTWARE}};

constexpr const char* kUsage =
    "usage: concert safety status [--timeout-ms MS]\n"
    "       concert safety estop [--source "
    "front-left|front-right|rear-left|rear-right|wireless|software]\n"
    "                            [--release] [--reason TEXT] [--timeout-ms MS]\n"
    "       concert safety reset [--source NAME] [--reason TEXT] [--timeout-ms MS]";

struct Options {
  std::string verb;
  std::map<std::string, std::string> values;
  bool release = false;
};

Options parse(const std::vector<std::string>& args) {
  if (args.empty()) throw UsageError("safety: expected a verb: status, estop or reset");
  Options o{args[0], {}, false};
  if (o.verb != "status" && o.verb != "estop" && o.verb != "reset") {
    throw UsageError("safety: unknown verb '" + o.verb + "' (status, estop, reset)");
  }
  for (std::size_t i = 1; i < args.size(); ++i) {
    const auto& a = args[i];
    if (a == "--release" && o.verb == "estop") {
      o.release = true;
    } else if (a == "--timeout-ms" ||
               ((a == "--source" || a == "--reason") && o.verb != "status")) {
      if (i + 1 >= args.size())
        throw UsageError("safety " + o.verb + ": option " + a + " needs a value");
      o.values[a] = args[++i];
    } else {
      throw UsageError("safety " + o.verb + ": unknown argument '" + a + "'");
    }
  }
  return o;
}

std::chrono::milliseconds timeout(const Options& o) {
  const auto it = o.values.find("--timeout-ms");
  if (it == o.values.end()) return 5000ms;
  std::size_t used = 0;
  long ms = -1;
  try {
    ms = std::stol(it->second, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != it->second.size() || ms < 1 || ms > 600'000) {
    throw UsageError("safety " + o.verb + ": --timeout-ms: '" + it->second +
                     "' is not a number of milliseconds (1..600000)");
  }
  return std::chrono::milliseconds(ms);
}

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string describe(const msg::SafetyState& s) {
  if (s.mode() == msg::SAFETY_RUNNING) return "RUNNING";
  std::string text = "STOPPED (reset required)";
  for (const auto& c : s.causes()) text += "\n  " + c;
  return text;
}

/// Waits for a SafetyState sample satisfying `accept`, or nullopt at the deadline.
template <class F>
std::optional<msg::SafetyState> wait_state(dds::Reader<msg::SafetyState>& reader,
                                           std::chrono::milliseconds limit, F accept) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = reader.wait(50ms); s && accept(*s)) return s;
  }
  return std::nullopt;
}

int status(const Options& o, dds::Participant& p, std::ostream& out) {
  dds::Reader<msg::SafetyState> states(p, dds::topics::safety_state);
  const auto s = wait_state(states, timeout(o), [](const auto&) { return true; });
  if (!s)
    throw Failure("no safety state on domain " + std::to_string(p.domain_id()) +
                  " (is concert_safety running?)");
  out << "safety: " << describe(*s) << "\n";
  return 0;
}

int estop(const Options& o, dds::Participant& p, std::ostream& out) {
  const auto name = o.values.count("--source") ? o.values.at("--source") : "software";
  const auto source = kSources.find(name);
  if (source == kSources.end()) {
    throw UsageError(
        "safety estop: --source: '" + name +
        "' is not front-left, front-right, rear-left, rear-right, wireless or software");
  }
  dds::Writer<msg::EStopInput> writer(p, dds::topics::estop);
  if (!writer.wait_for_readers(1, timeout(o))) {
    throw Failure("no safety service on domain " + std::to_string(p.domain_id()) +
                  " read the e-stop input");
  }
  msg::EStopInput input;
  input.source(source->second);
  input.engaged(!o.release);
  input.stamp_ns(now_ns());
  input.reason(o.values.count("--reason") ? o.values.at("--reason") : "concert safety estop");
  writer.write(input);
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(timeout(o)).count();
  if (writer.get()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
          static_cast<int32_t>(ns / 1'000'000'000), static_cast<uint32_t>(ns % 1'000'000'000))) !=
      eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    throw Failure("the safety service did not acknowledge the e-stop input");
  }
  out << "safety: e-stop " << name << (o.release ? " released" : " engaged") << "\n";
  return 0;
}

int reset(const Options& o, dds::Participant& p, std::ostream& out, std::ostream& err) {
  dds::Reader<msg::SafetyState> states(p, dds::topics::safety_state);
  dds::Reader<msg::ServiceStatus> statuses(p, dds::topics::status);
  dds::Writer<msg::SafetyReset> writer(p, dds::topics::safety_reset);
  if (!writer.wait_for_readers(1, timeout(o))) {
    throw Failure("no safety service on domain " + std::to_string(p.domain_id()) + " to reset");
  }
  const int64_t sent = now_ns();
  msg::SafetyReset request;
  request.request_id(static_cast<uint32_t>(sent / 1000 % 4'000'000'000));
  request.stamp_ns(sent);
  request.source(o.values.count("--source") ? o.values.at("--source")
                                            : "concert safety reset@" + dds::host_name());
  request.reason(o.values.count("--reason") ? o.values.at("--reason") : "");
  // Heartbeats repeat the service's last message with a fresh stamp, so a refusal is
  // recognised by naming this request's source, not by its time.
  const std::string refusal = "reset by " + request.source() + " refused";
  writer.write(request);
  // The service answers a reset with a state publication stamped after it, but it also
  // publishes states for other reasons (an input just released, a heartbeat): a STOPPED state
  // alone is no answer. Success is a RUNNING state; refusal is the service's status naming
  // the reason. Wait (bounded) for either.
  std::string why = "reset refused (no reason received)";
  std::optional<msg::SafetyState> last;
  const auto deadline = std::chrono::steady_clock::now() + timeout(o);
  while (std::chrono::steady_clock::now() < deadline) {
    while (auto st = states.take()) {
      if (st->stamp_ns() < sent) continue;
      last = *st;
      if (st->mode() == msg::SAFETY_RUNNING) {
        out << "safety: " << describe(*st) << "\n";
        return 0;
      }
    }
    const auto status = statuses.wait(20ms);
    if (status && status->service() == "safety" && status->stamp_ns() >= sent &&
        status->message().find(refusal) != std::string::npos) {
      why = status->message();
      break;
    }
  }
  if (last) {
    out << "safety: " << describe(*last) << "\n";
  } else if (why.find(refusal) == std::string::npos) {
    throw Failure("the safety service did not answer the reset");
  }
  err << "concert safety reset: " << why << "\n";
  return 1;
}

}  // namespace

int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    const auto o = parse(args);
    timeout(o);  // validate before touching DDS
    dds::Participant participant({.name = "concert-safety-cli"});
    if (o.verb == "status") return status(o, participant, out);
    if (o.verb == "estop") return estop(o, participant, out);
    return reset(o, participant, out, err);
  } catch (const UsageError& e) {
    err << "concert " << e.what() << "\n" << kUsage << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "concert safety: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace concert::safety
