#include "status_verbs.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/common/text.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/idl_schema/cdr.hpp"

namespace concert::tool {
namespace {

std::string state_name(msg::ServiceState s) {
  switch (s) {
    case msg::SERVICE_STARTING: return "starting";
    case msg::SERVICE_READY: return "ready";
    case msg::SERVICE_RECONFIGURING: return "reconfiguring";
    case msg::SERVICE_ERROR: return "error";
    case msg::SERVICE_STOPPED: return "stopped";
  }
  return "unknown";
}

}  // namespace

std::vector<ServiceRow> read_statuses(int32_t domain, std::chrono::milliseconds wait,
                                      std::optional<SafetyRow>* safety) {
  dds::Participant participant({.name = "concert-status", .domain_id = domain});
  std::mutex mutex;
  std::map<uint32_t, msg::ServiceStatus> latest;
  std::optional<SafetyRow> safety_seen;
  dds::Reader<msg::ServiceStatus> reader(participant, dds::topics::status, [&](const msg::ServiceStatus& s, const auto&) {
    std::lock_guard lock(mutex);
    latest[s.id()] = s;
  });
  std::optional<dds::Reader<msg::SafetyState>> safety_reader;
  if (safety != nullptr) {
    safety_reader.emplace(participant, dds::topics::safety_state,
                          [&](const msg::SafetyState& s, const auto&) {
                            std::lock_guard lock(mutex);
                            safety_seen = SafetyRow{s.mode() == msg::SAFETY_STOPPED, s.causes()};
                          });
  }
  // Listening is the verb's job here: statuses are heartbeats, so every running service is
  // heard within `wait` (the --timeout the user chose).
  std::this_thread::sleep_for(wait);
  std::lock_guard lock(mutex);
  if (safety != nullptr) *safety = safety_seen;
  std::vector<ServiceRow> rows;
  const int64_t now = now_ns();
  for (const auto& [id, s] : latest) {
    rows.push_back({s.service(), s.host(), state_name(s.state()), s.model_version(), s.model_hash(),
                    s.refusals(), s.message(), static_cast<double>(now - s.stamp_ns()) / 1e9});
  }
  std::sort(rows.begin(), rows.end(), [](const ServiceRow& a, const ServiceRow& b) {
    return std::tie(a.service, a.host) < std::tie(b.service, b.host);
  });
  return rows;
}

namespace {
/// "sha256:0123456789ab..." -> "0123456789ab" (the first 12 hex digits), "-" for none.
std::string short_hash(const std::string& hash) {
  if (hash.empty()) return "-";
  const auto colon = hash.find(':');
  return hash.substr(colon == std::string::npos ? 0 : colon + 1, 12);
}
}  // namespace

ModelAgreement model_agreement(const std::vector<ServiceRow>& rows) {
  ModelAgreement a;
  for (const auto& r : rows) {
    if (r.state == "stopped" || r.model_version == 0) continue;
    if (r.model_version > a.version || (r.model_version == a.version && a.hash.empty())) {
      a.version = r.model_version;
      a.hash = r.model_hash;
    }
  }
  for (const auto& r : rows) {
    if (r.state == "stopped" || r.model_version == 0) continue;
    const bool other_hash = !r.model_hash.empty() && !a.hash.empty() && r.model_hash != a.hash;
    if (r.model_version != a.version || other_hash) {
      a.disagreeing.push_back(r.service + "@" + r.host + " runs " +
                              std::to_string(r.model_version) + " (" + short_hash(r.model_hash) +
                              ")");
    }
  }
  return a;
}

std::vector<std::string> status_problems(const std::vector<ServiceRow>& rows) {
  std::vector<std::string> problems;
  for (const auto& r : rows) {
    if (r.state == "stopped" || r.state == "error") {
      problems.push_back(r.service + "@" + r.host + " is " + r.state + ": " + r.message);
    }
  }
  const ModelAgreement a = model_agreement(rows);
  if (!a.disagreeing.empty()) {
    std::string text = "the services disagree on the model: the newest is version " +
                       std::to_string(a.version) + " (" + short_hash(a.hash) + ") but";
    for (const auto& d : a.disagreeing) text += " " + d + ";";
    text.pop_back();
    problems.push_back(text);
  }
  for (const auto& r : rows) {
    if (r.refusals > 0) {
      problems.push_back(r.service + "@" + r.host + " refused " + std::to_string(r.refusals) +
                         " input" + (r.refusals == 1 ? "" : "s") +
                         " since it started (its log says which)");
    }
  }
  return problems;
}

std::vector<std::string> safety_problems(const std::optional<SafetyRow>& safety) {
  if (!safety) return {"no safety state heard on concert/safety/state (is concert_safety running?)"};
  if (!safety->stopped) return {};
  std::string text = "safety is STOPPED";
  for (size_t i = 0; i < safety->causes.size(); ++i) text += (i == 0 ? ": " : "; ") + safety->causes[i];
  text += " (release the e-stops, then `concert safety reset`)";
  return {text};
}

namespace {

/// Services that run on the robot model (discovery works on the module tree instead).
const std::set<std::string> kModelConsumers = {"modelgen", "robot", "safety", "planner", "nav",
                                               "drill", "collab", "surface_finish"};
/// Statuses are latched, but a new reader needs discovery first: before declaring everyone
/// ready, give every running service this long to be heard.
constexpr auto kSettle = std::chrono::milliseconds(1000);

/// Waits until every model consumer is ready at `version` or later, printing when each got
/// there. Model consumers: the services named in `only`, else the stack's model consumers and
/// any other service that reports a model version.
int until_version(int32_t domain, uint32_t version, const std::vector<std::string>& only, long timeout_ms,
                  std::ostream& out, std::ostream& err) {
  using Clock = std::chrono::steady_clock;
  dds::Participant participant({.name = "concert-status", .domain_id = domain});
  std::mutex mutex;
  std::map<std::string, msg::ServiceStatus> latest;  // "service@host"
  dds::Reader<msg::ServiceStatus> reader(participant, dds::topics::status, [&](const msg::ServiceStatus& s, const auto&) {
    std::lock_guard lock(mutex);
    latest[s.service() + "@" + s.host()] = s;
  });
  const auto t0 = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  auto consumer = [&](const msg::ServiceStatus& s) {
    if (!only.empty()) return std::find(only.begin(), only.end(), s.service()) != only.end();
    return kModelConsumers.count(s.service()) > 0 || s.model_version() != 0;
  };
  out << std::fixed << std::setprecision(3) << "[" << std::setw(7) << 0.0 << " s] waiting for model version "
      << version << std::endl;
  std::set<std::string> done;
  while (Clock::now() - t0 < std::chrono::milliseconds(timeout_ms)) {
    {
      std::lock_guard lock(mutex);
      size_t consumers = 0;
      for (const auto& [key, s] : latest) {
        if (!consumer(s)) continue;
        ++consumers;
        if (s.state() == msg::SERVICE_READY && s.model_version() >= version && done.insert(key).second) {
          out << "[" << std::setw(7) << elapsed() << " s] " << key << " ready at model version " << s.model_version()
              << std::endl;
        }
      }
      const bool named_all = only.empty() || std::all_of(only.begin(), only.end(), [&](const std::string& n) {
        return std::any_of(done.begin(), done.end(), [&](const std::string& k) { return k.rfind(n + "@", 0) == 0; });
      });
      // Ready is not enough: every consumer must run the same model (version and hash).
      std::vector<ServiceRow> rows;
      for (const auto& [key, s] : latest) {
        if (consumer(s))
          rows.push_back(
              {s.service(), s.host(), state_name(s.state()), s.model_version(), s.model_hash()});
      }
      const bool agree = model_agreement(rows).disagreeing.empty();
      if (consumers > 0 && done.size() == consumers && named_all && agree &&
          Clock::now() - t0 >= kSettle)
        return 0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::lock_guard lock(mutex);
  err << "concert status: not every service is ready at model version " << version << " after " << timeout_ms
      << " ms:";
  for (const auto& [key, s] : latest) {
    if (consumer(s) && !done.count(key)) {
      err << " " << key << " is " << state_name(s.state()) << " at " << s.model_version() << " (" << s.message() << ")";
    }
  }
  if (latest.empty()) err << " no service reported";
  std::vector<ServiceRow> rows;
  for (const auto& [key, s] : latest) {
    if (consumer(s))
      rows.push_back(
          {s.service(), s.host(), state_name(s.state()), s.model_version(), s.model_hash()});
  }
  for (const auto& d : model_agreement(rows).disagreeing) err << "; disagrees: " << d;
  err << "\n";
  return 1;
}

struct StatusOptions {
  cli::DdsOptions dds;
  uint32_t until_version = 0;
  std::string services;
  bool check = false;
};

int status(const StatusOptions& o, std::ostream& out, std::ostream& err) {
  const int32_t domain = o.dds.domain_id();
  if (o.until_version > 0) {
    const double timeout_s = o.dds.timeout_given ? o.dds.timeout_s : 30.0;
    return until_version(domain, o.until_version, split(o.services),
                         std::llround(timeout_s * 1000.0), out, err);
  }
  std::optional<SafetyRow> safety;
  const auto rows = read_statuses(domain, o.dds.timeout(), &safety);
  auto problems = status_problems(rows);
  for (auto& p : safety_problems(safety)) problems.push_back(std::move(p));
  if (o.dds.json) {
    idl::Json arr = idl::Json::array();
    for (const auto& r : rows) {
      arr.push_back({{"service", r.service},
                     {"host", r.host},
                     {"state", r.state},
                     {"model_version", r.model_version},
                     {"model_hash", r.model_hash},
                     {"refusals", r.refusals},
                     {"message", r.message},
                     {"age_s", r.age_s}});
    }
    out << arr.dump(2) << "\n";
    if (o.check) {
      for (const auto& p : problems) err << "concert status: " << p << "\n";
    }
    return o.check && !problems.empty() ? 1 : 0;
  }
  if (rows.empty()) {
    err << "concert status: no service reported on domain " << domain << " within "
        << o.dds.timeout_s << " s\n";
    return 1;
  }
  out << std::left << std::setw(16) << "SERVICE" << std::setw(18) << "HOST" << std::setw(15)
      << "STATE" << std::setw(7) << "MODEL" << std::setw(14) << "HASH" << std::setw(9) << "REFUSED"
      << std::setw(9) << "AGE"
      << "MESSAGE\n";
  const ModelAgreement agreement = model_agreement(rows);
  for (const auto& r : rows) {
    std::ostringstream age;
    age << std::fixed << std::setprecision(1) << r.age_s << "s";
    const bool odd = std::any_of(
        agreement.disagreeing.begin(), agreement.disagreeing.end(),
        [&](const std::string& d) { return d.rfind(r.service + "@" + r.host + " ", 0) == 0; });
    out << std::setw(16) << r.service << std::setw(18) << r.host << std::setw(15) << r.state
        << std::setw(7) << (std::to_string(r.model_version) + (odd ? "!" : "")) << std::setw(14)
        << short_hash(r.model_hash) << std::setw(9) << r.refusals << std::setw(9) << age.str()
        << r.message << "\n";
  }
  if (agreement.version > 0) {
    out << (agreement.disagreeing.empty() ? "every service runs model version "
                                          : "DISAGREEMENT: the newest model is version ")
        << agreement.version << " (" << short_hash(agreement.hash) << ")";
    for (const auto& d : agreement.disagreeing) out << "; " << d;
    out << "\n";
  }
  if (!safety) {
    out << "safety: no state heard\n";
  } else {
    out << "safety: " << (safety->stopped ? "STOPPED" : "RUNNING");
    for (size_t i = 0; i < safety->causes.size(); ++i) out << (i == 0 ? ": " : "; ") << safety->causes[i];
    out << "\n";
  }
  if (!o.check) return 0;
  for (const auto& p : problems) err << "concert status: " << p << "\n";
  return problems.empty() ? 0 : 1;
}

}  // namespace

void register_status_verb(cli::Cli& concert) {
  auto o = std::make_shared<StatusOptions>();
  CLI::App& verb = concert.verb(
      concert.app(), "status",
      "every service: host, state, model version and hash, refusals, last message; or wait until "
      "every model consumer is ready at a version (and they agree on its hash)",
      [&concert, o] { return status(*o, concert.out(), concert.err()); });
  concert.add_dds_options(
      verb, o->dds, 1.5,
      "how long to listen for the services (with --until-version: how long to wait, default 30)");
  cli::Cli::add_deprecated_ms_option(verb, "--wait-ms", o->dds.timeout_s,
                                     verb.get_option("--timeout"));
  verb.add_option("--until-version", o->until_version,
                  "wait until every model consumer is ready at version N or later")
      ->type_name("N")
      ->check(cli::number(1, 4e9, true));
  verb.add_flag("--check", o->check,
                "exit 1 unless the stack is ready to work: a service stopped or in error, the "
                "services disagreeing on the model, a service that refused input, or the safety "
                "layer STOPPED or not heard (each problem on stderr)");
  verb.add_option("--services", o->services,
                  "with --until-version: only these services (comma-separated)")
      ->type_name("a,b");
}

}  // namespace concert::tool
