// `concert drill run|status|abort`: missions to the drill service and what it reports.

#include "drill/cli.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "concert/common/clock.hpp"
#include "concert/common/resend.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"

namespace concert::drill {
namespace {

namespace cdds = concert::dds;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* state_name(msg::DrillMissionState s) {
  switch (s) {
    case msg::DRILL_IDLE:
      return "idle";
    case msg::DRILL_RUNNING:
      return "running";
    case msg::DRILL_SUCCEEDED:
      return "succeeded";
    case msg::DRILL_FAILED:
      return "failed";
    case msg::DRILL_ABORTED:
      return "aborted";
  }
  return "?";
}

const char* area_state(msg::DrillAreaState s) {
  switch (s) {
    case msg::AREA_PENDING:
      return "pending";
    case msg::AREA_ACTIVE:
      return "active";
    case msg::AREA_DONE:
      return "done";
    case msg::AREA_FAILED:
      return "failed";
    case msg::AREA_SKIPPED:
      return "skipped";
  }
  return "?";
}

const char* hole_state(msg::DrillHoleState s) {
  switch (s) {
    case msg::HOLE_PENDING:
      return "pending";
    case msg::HOLE_DRILLED:
      return "drilled";
    case msg::HOLE_FAILED:
      return "failed";
    case msg::HOLE_SKIPPED:
      return "skipped";
  }
  return "?";
}

const char* reach_name(msg::DrillReach r) {
  switch (r) {
    case msg::REACH_REACHABLE:
      return "reachable";
    case msg::REACH_UNREACHABLE:
      return "unreachable";
    case msg::REACH_UNKNOWN:
      break;
  }
  return "unknown";
}

nlohmann::ordered_json status_json(const msg::DrillStatus& s) {
  nlohmann::ordered_json areas = nlohmann::ordered_json::array();
  for (const auto& a : s.areas()) {
    nlohmann::ordered_json holes = nlohmann::ordered_json::array();
    for (const auto& h : a.holes()) {
      const auto& p = h.frame().position();
      holes.push_back({{"label", h.label()},
                       {"state", hole_state(h.state())},
                       {"reason", h.reason()},
                       {"reach", reach_name(h.reach())},
                       {"reach_reason", h.reach_reason()},
                       {"position", {p.x(), p.y(), p.z()}},
                       {"time", {{"align", h.time_align()}, {"drill", h.time_drill()}, {"retract", h.time_retract()}}}});
    }
    areas.push_back({{"name", a.name()},
                     {"state", area_state(a.state())},
                     {"reason", a.reason()},
                     {"time",
                      {{"approach", a.time_approach()},
                       {"detect", a.time_detect()},
                       {"survey", a.time_survey()},
                       {"place", a.time_place()}}},
                     {"holes", holes}});
  }
  return {{"mission_id", s.mission_id()},
          {"mission", s.mission()},
          {"state", state_name(s.state())},
          {"active", s.active()},
          {"reason", s.reason()},
          {"holes_drilled", s.holes_drilled()},
          {"holes_marked", s.holes_marked()},
          {"time",
           {{"navigate", s.time_navigate()},
            {"plan", s.time_plan()},
            {"execute", s.time_execute()},
            {"drill", s.time_drill()},
            {"total", s.time_total()}}},
          {"areas", areas}};
}

void print_report(const msg::DrillStatus& s, std::ostream& out) {
  out << "mission '" << s.mission() << "' " << state_name(s.state()) << ": " << s.holes_drilled()
      << " of " << s.holes_marked() << " marked holes drilled";
  if (!s.reason().empty()) out << " (" << s.reason() << ")";
  out << "\n";
  for (const auto& a : s.areas()) {
    out << "  area '" << a.name() << "': " << area_state(a.state());
    if (!a.reason().empty()) out << ": " << a.reason();
    out << std::fixed << std::setprecision(1) << " (approach " << a.time_approach() << " s, detect "
        << a.time_detect() << " s, survey " << a.time_survey() << " s, place " << a.time_place() << " s)"
        << std::defaultfloat << "\n";
    for (const auto& h : a.holes()) {
      const auto& p = h.frame().position();
      out << "    " << std::left << std::setw(18) << h.label() << std::right << " " << std::setw(8)
          << hole_state(h.state()) << std::fixed << std::setprecision(3) << "  at (" << p.x()
          << ", " << p.y() << ", " << p.z() << ")" << std::defaultfloat;
      if (!h.reason().empty()) out << ": " << h.reason();
      // Reachable holes say at which thrust (their reason tells the rest); an unreachable one's
      // reason already names why.
      if (h.reach() == msg::REACH_REACHABLE) out << " (reachable: " << h.reach_reason() << ")";
      if (h.state() == msg::HOLE_DRILLED || h.state() == msg::HOLE_FAILED) {
        out << std::fixed << std::setprecision(1) << "; align " << h.time_align() << " s, drill "
            << h.time_drill() << " s, retract " << h.time_retract() << " s" << std::defaultfloat;
      }
      out << "\n";
    }
  }
  out << std::fixed << std::setprecision(1) << "  time: navigate " << s.time_navigate()
      << " s, plan " << s.time_plan() << " s, execute " << s.time_execute() << " s, drill "
      << s.time_drill() << " s, total " << s.time_total() << " s\n"
      << std::defaultfloat;
}

std::chrono::milliseconds left_until(Clock::time_point deadline) {
  return std::max(std::chrono::milliseconds(0),
                  std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
}

struct RunOptions {
  std::string mission;
  bool resume = false;
  bool no_wait = false;
  uint32_t mission_id = std::random_device{}() & 0x7fffffffu;
  cli::DdsOptions dds;
};

int run_mission(const RunOptions& o, std::ostream& out, std::ostream& err) {
  std::ifstream in(o.mission);
  if (!in) {
    err << "concert drill run: cannot read mission file '" << o.mission << "'\n";
    return 1;
  }
  std::stringstream text;
  text << in.rdbuf();
  cdds::Participant participant({.name = "concert_drill", .domain_id = o.dds.domain_id()});
  cdds::Reader<msg::DrillStatus> statuses(participant, cdds::topics::drill_status);
  cdds::Writer<msg::DrillMission> missions(participant, cdds::topics::drill_mission);
  const auto deadline = Clock::now() + o.dds.timeout();
  if (!missions.wait_for_readers(1,
                                 std::min(left_until(deadline), std::chrono::milliseconds(5000)))) {
    err << "concert drill run: no drill service listening on domain " << participant.domain_id()
        << " (is concert_drill running?)\n";
    return 1;
  }
  msg::DrillMission m;
  m.mission_id(o.mission_id);
  m.stamp_ns(now_ns());
  m.source("concert drill");
  m.name(fs::path(o.mission).filename().string());
  m.yaml(text.str());
  m.base_dir(fs::absolute(fs::path(o.mission)).parent_path().string());
  m.resume(o.resume);
  // The reader matched may be another tool's (the GUI's gateway, a recorder) before the drill
  // service's: the mission is written again every second until a status names it (the service
  // takes a mission it has seen, same id and stamp, once). --no-wait writes it once.
  std::optional<msg::DrillStatus> first;
  resend_until_answered([&] { missions.write(m); },
                        [&](Clock::time_point until) {
                          while (!o.no_wait && !first && Clock::now() < until) {
                            const auto s = statuses.wait(left_until(until));
                            if (s && s->mission_id() == o.mission_id) first = s;
                          }
                          return o.no_wait || first.has_value();
                        },
                        deadline);
  if (!o.dds.json) out << "mission " << o.mission_id << " sent (" << m.name() << ")" << std::endl;
  if (o.no_wait) return 0;
  if (!first) {
    err << "concert drill run: the drill service did not take mission " << o.mission_id
        << " within " << o.dds.timeout_s << " s\n";
    return 1;
  }
  std::string printed;
  std::set<std::string> judged;  // "area/hole" whose reach was printed
  while (first || left_until(deadline).count() > 0) {
    const auto s = first ? first : statuses.wait(left_until(deadline));
    first.reset();
    if (!s || s->mission_id() != o.mission_id || s->state() == msg::DRILL_IDLE) continue;
    if (s->state() == msg::DRILL_RUNNING) {
      if (!o.dds.json && s->active() != printed) {
        printed = s->active();
        out << "  " << s->active() << std::endl;
      }
      // Each hole's reach as soon as it was judged, before anything moves for it.
      for (const auto& a : s->areas()) {
        for (const auto& h : a.holes()) {
          if (o.dds.json || h.reach() == msg::REACH_UNKNOWN || !judged.insert(a.name() + "/" + h.label()).second)
            continue;
          out << "    area '" << a.name() << "' hole '" << h.label() << "': " << reach_name(h.reach()) << ": "
              << h.reach_reason() << std::endl;
        }
      }
      continue;
    }
    if (o.dds.json) {
      out << status_json(*s).dump() << std::endl;
    } else {
      print_report(*s, out);
    }
    return s->state() == msg::DRILL_SUCCEEDED ? 0 : 1;
  }
  err << "concert drill run: the mission did not end within " << o.dds.timeout_s
      << " s (it keeps running; concert drill abort stops it)\n";
  return 1;
}

int run_status(const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Participant participant({.name = "concert_drill", .domain_id = dds.domain_id()});
  cdds::Reader<msg::DrillStatus> statuses(participant, cdds::topics::drill_status);
  std::optional<msg::DrillStatus> latest;
  const auto deadline = Clock::now() + dds.timeout();
  while (left_until(deadline).count() > 0) {
    const auto s = statuses.wait(std::min(left_until(deadline), std::chrono::milliseconds(300)));
    if (!s) {
      if (latest) break;  // the latched statuses have arrived
      continue;
    }
    if (!latest || s->stamp_ns() >= latest->stamp_ns()) latest = s;
  }
  if (!latest) {
    err << "concert drill status: no mission status on domain " << participant.domain_id()
        << " (no mission run yet, or no drill service)\n";
    return 1;
  }
  if (dds.json) {
    out << status_json(*latest).dump() << std::endl;
  } else if (latest->state() == msg::DRILL_RUNNING) {
    out << "mission '" << latest->mission() << "' (" << latest->mission_id()
        << ") running: " << latest->active() << "\n";
    print_report(*latest, out);
  } else {
    print_report(*latest, out);
  }
  return 0;
}

int run_abort(const std::string& reason, const cli::DdsOptions& dds, std::ostream& out,
              std::ostream& err) {
  cdds::Participant participant({.name = "concert_drill", .domain_id = dds.domain_id()});
  cdds::Writer<msg::DrillAbort> aborts(participant, cdds::topics::drill_abort);
  if (!aborts.wait_for_readers(1, std::min(dds.timeout(), std::chrono::milliseconds(5000)))) {
    err << "concert drill abort: no drill service listening on domain " << participant.domain_id()
        << "\n";
    return 1;
  }
  msg::DrillAbort a;
  a.mission_id(0);
  a.stamp_ns(now_ns());
  a.source("concert drill");
  a.reason(reason);
  aborts.write(a);
  if (aborts.get()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(2, 0)) !=
      eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    err << "concert drill abort: the drill service did not acknowledge the abort\n";
    return 1;
  }
  out << "abort sent\n";
  return 0;
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& drill = concert.group(concert.app(), "drill", "drilling missions (drill service)");
  {
    auto o = std::make_shared<RunOptions>();
    CLI::App& verb =
        concert.verb(drill, "run", "run a drilling mission file and print its report",
                     [&concert, o] { return run_mission(*o, concert.out(), concert.err()); });
    verb.add_option("--mission", o->mission, "the mission file (services/drill/README.md)")
        ->required()
        ->type_name("FILE");
    verb.add_flag("--resume", o->resume, "skip the holes the latest run of this mission drilled");
    verb.add_option("--mission-id", o->mission_id, "the mission's id (default: random)")
        ->type_name("N")
        ->check(cli::number(1, 4294967295.0, true));
    verb.add_flag("--no-wait", o->no_wait, "send the mission and return");
    concert.add_dds_options(verb, o->dds, 1800.0, "how long to follow the mission");
  }
  {
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb =
        concert.verb(drill, "status", "the latest mission: active node, areas, holes, times",
                     [&concert, dds] { return run_status(*dds, concert.out(), concert.err()); });
    concert.add_dds_options(verb, *dds, 3.0, "how long to wait for the drill service's status");
  }
  {
    auto reason = std::make_shared<std::string>();
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(
        drill, "abort", "stop the running mission",
        [&concert, reason, dds] { return run_abort(*reason, *dds, concert.out(), concert.err()); });
    verb.add_option("--reason", *reason, "why (shown in the report)");
    concert.add_dds_options(verb, *dds, 5.0, "how long to wait for the drill service");
  }
}

}  // namespace concert::drill
