// `concert finish areas|spray|sand|status|abort`: requests to the surface finishing service and
// what it reports.

#include "surface_finish/cli.hpp"

#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "concert/common/resend.hpp"
#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"

namespace concert::surface_finish {
namespace {

namespace cdds = concert::dds;
using Clock = std::chrono::steady_clock;

std::chrono::milliseconds left_until(Clock::time_point deadline) {
  return std::max(std::chrono::milliseconds(0),
                  std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
}

const char* state_name(msg::FinishState s) {
  switch (s) {
    case msg::FINISH_IDLE: return "idle";
    case msg::FINISH_RUNNING: return "running";
    case msg::FINISH_SUCCEEDED: return "succeeded";
    case msg::FINISH_FAILED: return "failed";
    case msg::FINISH_ABORTED: return "aborted";
  }
  return "?";
}

std::optional<msg::FinishAreas> read_areas(cdds::Participant& p, std::chrono::milliseconds timeout) {
  cdds::Reader<msg::FinishAreas> reader(p, cdds::topics::finish_areas);
  return reader.wait(timeout);
}

nlohmann::ordered_json areas_json(const msg::FinishAreas& a) {
  nlohmann::ordered_json j{{"model_version", a.model_version()}, {"tool", a.tool()},       {"reason", a.reason()},
                           {"wall_distance_m", a.wall_distance()}, {"standoff_m", a.standoff()},
                           {"areas", nlohmann::ordered_json::array()}};
  for (const auto& area : a.areas()) {
    j["areas"].push_back({{"id", area.id()}, {"x0", area.x0()}, {"x1", area.x1()}, {"y0", area.y0()}, {"y1", area.y1()}});
  }
  return j;
}

nlohmann::ordered_json status_json(const msg::FinishStatus& s) {
  nlohmann::ordered_json j{{"request_id", s.request_id()}, {"model_version", s.model_version()},
                           {"state", state_name(s.state())}, {"reason", s.reason()},
                           {"progress", s.progress()},      {"strokes", s.strokes()},
                           {"duration_s", s.duration()},    {"wall_distance_m", s.wall_distance()}};
  if (!s.report_json().empty()) j["report"] = nlohmann::json::parse(s.report_json(), nullptr, false);
  return j;
}

void print_status(const msg::FinishStatus& s, std::ostream& out) {
  out << "request " << s.request_id() << ": " << state_name(s.state());
  if (!s.reason().empty()) out << " (" << s.reason() << ")";
  out << ", " << s.strokes() << " strokes, " << s.duration() << " s path, progress " << static_cast<int>(s.progress() * 100) << " %\n";
  if (s.report_json().empty()) return;
  const auto r = nlohmann::json::parse(s.report_json(), nullptr, false);
  if (r.is_discarded()) return;
  char b[200];
  if (r.value("task", "") == "sand") {
    if (!r.contains("mean_n")) {
      out << "no stroke sanded\n";
      return;
    }
    std::snprintf(b, sizeof b,
                  "force (the robot's estimate) mean %.2f N, min %.2f N, max %.2f N; within +-%.1f "
                  "N of %.1f N for "
                  "%.1f %% of %.1f s of strokes (%.2f s outside)\n",
                  r.value("mean_n", 0.0), r.value("min_n", 0.0), r.value("max_n", 0.0),
                  r.value("tolerance_n", 0.0), r.value("force_setpoint_n", 0.0),
                  r.value("within_tolerance_percent", 0.0), r.value("stroke_time_s", 0.0),
                  r.value("time_outside_s", 0.0));
    out << b;
    return;
  }
  std::snprintf(b, sizeof b, "coverage %.2f %%, overspray %.3f m^2, max |dh| %.1f mm, max coat width error %.1f mm\n",
                r.value("coverage_percent", 0.0), r.value("overspray_m2", 0.0), r.value("max_abs_delta_h_mm", 0.0),
                r.value("max_width_error_mm", 0.0));
  out << b;
  for (const auto& c : r["coats"]) {
    std::snprintf(b, sizeof b, "  stroke %2d %-4s width %5.1f mm, %6.1f .. %6.1f mm, dh %+5.1f mm\n", c.value("stroke", 0),
                  c.value("direction", "").c_str(), c.value("width_mm", 0.0), c.value("bottom_mm", 0.0),
                  c.value("top_mm", 0.0), c.value("delta_h_mm", 0.0));
    out << b;
  }
}

int run_areas(const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Participant p({.name = "concert_finish", .domain_id = dds.domain_id()});
  const auto a = read_areas(p, dds.timeout());
  if (!a) {
    err << "concert finish areas: no areas on domain " << p.domain_id() << " (is concert_surface_finish running and ready?)\n";
    return 1;
  }
  if (dds.json) {
    out << areas_json(*a).dump() << std::endl;
    return 0;
  }
  if (!a->reason().empty()) {
    out << "model version " << a->model_version() << ": " << a->reason() << "\n";
    return 1;
  }
  out << "model version " << a->model_version() << ": " << a->tool() << ", stand " << a->wall_distance()
      << " m from the wall, tool " << a->standoff() << " m off it\n";
  for (const auto& area : a->areas()) {
    char b[160];
    std::snprintf(b, sizeof b, "  %-7s x [%6.2f, %6.2f] m, height [%5.2f, %5.2f] m (%.2f x %.2f m)\n", area.id().c_str(),
                  area.x0(), area.x1(), area.y0(), area.y1(), area.x1() - area.x0(), area.y1() - area.y0());
    out << b;
  }
  return 0;
}

struct RunOptions {
  std::string area;
  std::vector<double> rect;
  double speed = 0.0;
  double force = 30.0;
  bool no_wait = false;
  cli::DdsOptions dds;
};

int run_request(msg::FinishVerb verb, const RunOptions& o, std::ostream& out, std::ostream& err) {
  const char* name = verb == msg::FINISH_SPRAY ? "spray" : "sand";
  if (!o.rect.empty() && o.rect.size() != 4) {
    err << "concert finish " << name << ": --rect takes X0,X1,Y0,Y1 [m]\n";
    return 2;
  }
  cdds::Participant p({.name = "concert_finish", .domain_id = o.dds.domain_id()});
  const auto deadline = Clock::now() + o.dds.timeout();
  const auto a = read_areas(p, std::min(left_until(deadline), std::chrono::milliseconds(5000)));
  if (!a) {
    err << "concert finish " << name << ": no areas on domain " << p.domain_id() << " (is concert_surface_finish ready?)\n";
    return 1;
  }
  cdds::Reader<msg::FinishStatus> statuses(p, cdds::topics::finish_status);
  cdds::Writer<msg::FinishCommand> commands(p, cdds::topics::finish_command);
  if (!commands.wait_for_readers(1, std::min(left_until(deadline), std::chrono::milliseconds(5000)))) {
    err << "concert finish " << name << ": no surface finishing service listening\n";
    return 1;
  }
  std::mt19937 rng(static_cast<std::uint32_t>(now_ns()));
  msg::FinishCommand c;
  c.request_id(std::uniform_int_distribution<std::uint32_t>(1, 0x7fffffff)(rng));
  c.model_version(a->model_version());
  c.stamp_ns(now_ns());
  c.source("concert finish");
  c.verb(verb);
  c.area(o.area);
  if (o.rect.size() == 4) {
    c.has_rect(true);
    c.x0(o.rect[0]);
    c.x1(o.rect[1]);
    c.y0(o.rect[2]);
    c.y1(o.rect[3]);
  }
  c.speed(o.speed);
  c.force(o.force);
  // The command topic is volatile and the reader matched may be another tool's (the GUI's
  // gateway, a recorder) before the service's: the command is written again every second until
  // a status names the request (the service takes a request it has seen, same id and stamp,
  // once). --no-wait writes it once.
  std::optional<msg::FinishStatus> first;
  resend_until_answered(
      [&] { commands.write(c); },
      [&](Clock::time_point until) {
        while (!o.no_wait && !first && Clock::now() < until) {
          const auto s = statuses.wait(left_until(until));
          if (s && s->request_id() == c.request_id()) first = s;
        }
        return o.no_wait || first.has_value();
      },
      deadline);
  if (!o.dds.json) out << "request " << c.request_id() << " sent (" << name << " area '" << o.area << "')" << std::endl;
  if (o.no_wait) return 0;
  if (!first) {
    err << "concert finish " << name << ": the surface finishing service did not take request "
        << c.request_id() << " within " << o.dds.timeout_s << " s\n";
    return 1;
  }
  while (first || left_until(deadline).count() > 0) {
    const auto s = first ? first : statuses.wait(left_until(deadline));
    first.reset();
    if (!s || s->request_id() != c.request_id() || s->state() == msg::FINISH_RUNNING) continue;
    if (o.dds.json) {
      out << status_json(*s).dump() << std::endl;
    } else {
      print_status(*s, out);
    }
    return s->state() == msg::FINISH_SUCCEEDED ? 0 : 1;
  }
  err << "concert finish " << name << ": no result within " << o.dds.timeout_s << " s (concert finish abort stops it)\n";
  return 1;
}

int run_status(const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Participant p({.name = "concert_finish", .domain_id = dds.domain_id()});
  cdds::Reader<msg::FinishStatus> statuses(p, cdds::topics::finish_status);
  std::optional<msg::FinishStatus> latest;
  const auto deadline = Clock::now() + dds.timeout();
  while (left_until(deadline).count() > 0) {
    const auto s = statuses.wait(std::min(left_until(deadline), std::chrono::milliseconds(300)));
    if (!s) {
      if (latest) break;
      continue;
    }
    if (!latest || s->stamp_ns() >= latest->stamp_ns()) latest = s;
  }
  if (!latest) {
    err << "concert finish status: no run status on domain " << p.domain_id() << "\n";
    return 1;
  }
  if (dds.json) {
    out << status_json(*latest).dump() << std::endl;
  } else {
    print_status(*latest, out);
  }
  return 0;
}

int run_abort(const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Participant p({.name = "concert_finish", .domain_id = dds.domain_id()});
  cdds::Writer<msg::FinishCommand> commands(p, cdds::topics::finish_command);
  if (!commands.wait_for_readers(1, std::min(dds.timeout(), std::chrono::milliseconds(5000)))) {
    err << "concert finish abort: no surface finishing service listening\n";
    return 1;
  }
  msg::FinishCommand c;
  c.stamp_ns(now_ns());
  c.source("concert finish");
  c.verb(msg::FINISH_ABORT);
  commands.write(c);
  out << "abort sent\n";
  return 0;
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& finish = concert.group(concert.app(), "finish", "sanding and spraying of a wall area (surface_finish service)");
  {
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(finish, "areas", "the predetermined areas of the current model",
                                  [&concert, dds] { return run_areas(*dds, concert.out(), concert.err()); });
    concert.add_dds_options(verb, *dds, 5.0, "how long to wait for the areas");
  }
  for (const msg::FinishVerb v : {msg::FINISH_SPRAY, msg::FINISH_SAND}) {
    auto o = std::make_shared<RunOptions>();
    const bool spray = v == msg::FINISH_SPRAY;
    CLI::App& verb = concert.verb(finish, spray ? "spray" : "sand",
                                  spray ? "spray an area and print the coverage report" : "sand an area at a force",
                                  [&concert, o, v] { return run_request(v, *o, concert.out(), concert.err()); });
    verb.add_option("--area", o->area, "area id (concert finish areas)")->required();
    verb.add_option("--rect", o->rect, "a rectangle inside the area: X0,X1,Y0,Y1 [m]")->delimiter(',')->expected(4);
    verb.add_option("--speed", o->speed, "TCP speed along the strokes [m/s]")->check(cli::number(0.01, 1.0));
    if (!spray) verb.add_option("--force", o->force, "force setpoint [N]")->required()->check(cli::number(1.0, 200.0));
    verb.add_flag("--no-wait", o->no_wait, "send the request and return");
    concert.add_dds_options(verb, o->dds, 600.0, "how long to follow the run");
  }
  {
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(finish, "status", "the latest run's state and report",
                                  [&concert, dds] { return run_status(*dds, concert.out(), concert.err()); });
    concert.add_dds_options(verb, *dds, 3.0, "how long to wait for the statuses");
  }
  {
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(finish, "abort", "stop the running path",
                                  [&concert, dds] { return run_abort(*dds, concert.out(), concert.err()); });
    concert.add_dds_options(verb, *dds, 5.0, "how long to wait for the service");
  }
}

}  // namespace concert::surface_finish
