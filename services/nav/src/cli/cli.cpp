// `concert nav goto|cancel|init|status`: goals to the nav service and what it reports.

#include "nav/cli.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "concert/common/clock.hpp"
#include "concert/common/resend.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"

namespace concert::nav {
namespace {

namespace cdds = concert::dds;
using Clock = std::chrono::steady_clock;

const char* state_name(msg::NavState s) {
  switch (s) {
    case msg::NAV_IDLE:
      return "idle";
    case msg::NAV_PLANNING:
      return "planning";
    case msg::NAV_FOLLOWING:
      return "following";
    case msg::NAV_REACHED:
      return "reached";
    case msg::NAV_FAILED:
      return "failed";
    case msg::NAV_CANCELLED:
      return "cancelled";
    case msg::NAV_REFUSED:
      return "refused";
  }
  return "?";
}

const char* localisation_name(msg::LocalisationState s) {
  switch (s) {
    case msg::LOCALISATION_NONE:
      return "none";
    case msg::LOCALISATION_CONVERGING:
      return "converging";
    case msg::LOCALISATION_TRACKING:
      return "tracking";
    case msg::LOCALISATION_LOST:
      return "lost";
  }
  return "?";
}

bool final_state(msg::NavState s) {
  return s == msg::NAV_REACHED || s == msg::NAV_FAILED || s == msg::NAV_CANCELLED ||
         s == msg::NAV_REFUSED;
}

std::string pose_text(const msg::Pose2D& p) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << "(" << p.x() << ", " << p.y() << ", "
    << std::setprecision(1) << p.yaw() * 180.0 / M_PI << " deg)";
  return s.str();
}

nlohmann::ordered_json pose_json(const msg::Pose2D& p) {
  return {{"x", p.x()}, {"y", p.y()}, {"yaw", p.yaw()}};
}

nlohmann::ordered_json status_json(const msg::NavStatus& s) {
  return {{"request_id", s.request_id()},
          {"model_version", s.model_version()},
          {"state", state_name(s.state())},
          {"reason", s.reason()},
          {"goal", pose_json(s.goal())},
          {"pose", pose_json(s.pose())},
          {"distance_remaining", s.distance_remaining()},
          {"replans", s.replans()},
          {"position_error", s.position_error()},
          {"heading_error", s.heading_error()}};
}

template <class T>
bool acknowledged(cdds::Writer<T>& writer) {
  return writer.get()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(2, 0)) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
}

std::chrono::milliseconds left_until(Clock::time_point deadline) {
  return std::max(std::chrono::milliseconds(0),
                  std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
}

struct GotoOptions {
  std::vector<double> pose;  // X Y THETA
  std::string wall;
  std::vector<double> at;  // S H
  uint32_t request_id = std::random_device{}() & 0x7fffffffu;
  bool no_wait = false;
  cli::DdsOptions dds;
};

int run_goto(const GotoOptions& o, std::ostream& out, std::ostream& err) {
  const bool wall = !o.wall.empty();
  if (wall == !o.pose.empty())
    throw cli::UsageError("give either X Y THETA or --wall GLOBALID --at S H");
  if (wall && o.at.size() != 2) throw cli::UsageError("--wall needs --at S H");
  if (!wall && !o.at.empty()) throw cli::UsageError("--at goes with --wall");
  cdds::Participant participant({.name = "concert_nav", .domain_id = o.dds.domain_id()});
  cdds::Reader<msg::RobotModel> models(participant, cdds::topics::robot_model);
  cdds::Reader<msg::NavStatus> statuses(participant, cdds::topics::nav_status);
  cdds::Writer<msg::NavGoal> goals(participant, cdds::topics::nav_goal);
  const auto deadline = Clock::now() + o.dds.timeout();
  const auto model = models.wait(std::min(left_until(deadline), std::chrono::milliseconds(5000)));
  if (!model) {
    err << "concert nav goto: no robot model on domain " << participant.domain_id()
        << " (is concert_modelgen running?)\n";
    return 1;
  }
  if (!goals.wait_for_readers(1, std::min(left_until(deadline), std::chrono::milliseconds(5000)))) {
    err << "concert nav goto: no nav service listening on domain " << participant.domain_id()
        << " (is concert_nav running?)\n";
    return 1;
  }
  // The answer's path matched before the goal is sent (a status written before our reader
  // matched would reach us only through the late joiner's history).
  if (!statuses.wait_for_writers(1, std::min(left_until(deadline), std::chrono::milliseconds(5000)))) {
    err << "concert nav goto: the nav service's statuses do not reach this client on domain "
        << participant.domain_id() << "\n";
    return 1;
  }
  msg::NavGoal g;
  g.request_id(o.request_id);
  g.model_version(model->version());
  g.stamp_ns(now_ns());
  g.source("concert nav");
  if (wall) {
    g.kind(msg::NAV_GOAL_WALL);
    g.wall(o.wall);
    g.s(o.at[0]);
    g.h(o.at[1]);
  } else {
    g.kind(msg::NAV_GOAL_POSE);
    g.pose().x(o.pose[0]);
    g.pose().y(o.pose[1]);
    g.pose().yaw(o.pose[2]);
  }
  // The reader matched first may be another tool's (the GUI's gateway, a recorder) before the
  // nav service's: the goal is written again every second until a status names it (the
  // service takes a goal it has seen, same id and stamp, once). --no-wait writes it once.
  std::optional<msg::NavStatus> first;
  const bool taken = resend_until_answered([&] { goals.write(g); },
                                           [&](Clock::time_point until) {
                                             while (!o.no_wait && !first && Clock::now() < until) {
                                               const auto s = statuses.wait(left_until(until));
                                               if (s && s->request_id() == o.request_id) first = s;
                                             }
                                             return o.no_wait || first.has_value();
                                           },
                                           deadline);
  if (o.dds.json) {
    out << nlohmann::ordered_json{{"request_id", o.request_id}, {"model_version", model->version()}}
               .dump()
        << std::endl;
  } else {
    out << "goal " << o.request_id << " sent for model version " << model->version() << "\n";
  }
  if (o.no_wait) return 0;
  if (!taken) {
    err << "concert nav goto: the nav service did not take goal " << o.request_id << " within "
        << o.dds.timeout_s << " s\n";
    return 1;
  }
  msg::NavState printed = msg::NAV_IDLE;
  auto last_print = Clock::now();
  while (first || left_until(deadline).count() > 0) {
    const auto s = first ? first : statuses.wait(left_until(deadline));
    first.reset();
    if (!s || s->request_id() != o.request_id) continue;
    // Progress arrives several times a second: a line per state change, else every 2 s.
    const bool changed = s->state() != printed;
    if (changed || final_state(s->state()) || Clock::now() - last_print > std::chrono::seconds(2)) {
      printed = s->state();
      last_print = Clock::now();
      if (o.dds.json) {
        out << status_json(*s).dump() << std::endl;
      } else {
        out << "  " << state_name(s->state()) << " at " << pose_text(s->pose());
        if (s->state() == msg::NAV_FOLLOWING) {
          out << std::fixed << std::setprecision(2) << ", " << s->distance_remaining() << " m to go"
              << std::defaultfloat;
        }
        if (s->state() == msg::NAV_REACHED) {
          out << std::fixed << std::setprecision(3) << ", " << s->position_error() << " m and "
              << std::setprecision(2) << s->heading_error() * 180.0 / M_PI << " deg from the goal "
              << pose_text(s->goal()) << std::defaultfloat;
        }
        if (!s->reason().empty()) out << ": " << s->reason();
        out << std::endl;
      }
    }
    if (s->state() == msg::NAV_REACHED) return 0;
    if (final_state(s->state())) {
      err << "concert nav goto: " << state_name(s->state()) << ": " << s->reason() << "\n";
      return 1;
    }
  }
  err << "concert nav goto: no final result within " << o.dds.timeout_s
      << " s (the goal keeps running; "
      << "concert nav cancel stops it)\n";
  return 1;
}

int run_cancel(uint32_t request_id, const cli::DdsOptions& dds, std::ostream& out,
               std::ostream& err) {
  cdds::Participant participant({.name = "concert_nav", .domain_id = dds.domain_id()});
  cdds::Writer<msg::NavCancel> cancels(participant, cdds::topics::nav_cancel);
  if (!cancels.wait_for_readers(1, std::min(dds.timeout(), std::chrono::milliseconds(5000)))) {
    err << "concert nav cancel: no nav service listening on domain " << participant.domain_id()
        << "\n";
    return 1;
  }
  msg::NavCancel c;
  c.request_id(request_id);
  c.stamp_ns(now_ns());
  c.source("concert nav");
  cancels.write(c);
  // A reliable command: make sure it arrived before the participant goes.
  if (!acknowledged(cancels)) {
    err << "concert nav cancel: the nav service did not acknowledge the cancel\n";
    return 1;
  }
  out << "cancel sent" << (request_id ? " for goal " + std::to_string(request_id) : std::string())
      << "\n";
  return 0;
}

struct InitOptions {
  std::vector<double> pose;
  double std_xy = 0.0;
  double std_yaw = 0.0;
  cli::DdsOptions dds;
};

int run_init(const InitOptions& o, std::ostream& out, std::ostream& err) {
  cdds::Participant participant({.name = "concert_nav", .domain_id = o.dds.domain_id()});
  cdds::Writer<msg::NavInitialPose> poses(participant, cdds::topics::nav_initial_pose);
  if (!poses.wait_for_readers(1, std::min(o.dds.timeout(), std::chrono::milliseconds(5000)))) {
    err << "concert nav init: no nav service listening on domain " << participant.domain_id()
        << "\n";
    return 1;
  }
  msg::NavInitialPose p;
  p.stamp_ns(now_ns());
  p.source("concert nav");
  p.pose().x(o.pose[0]);
  p.pose().y(o.pose[1]);
  p.pose().yaw(o.pose[2]);
  p.std_xy(o.std_xy);
  p.std_yaw(o.std_yaw);
  poses.write(p);
  if (!acknowledged(poses)) {
    err << "concert nav init: the nav service did not acknowledge the initial pose\n";
    return 1;
  }
  out << "initial pose " << pose_text(p.pose()) << " sent\n";
  return 0;
}

int run_status(const cli::DdsOptions& dds, std::ostream& out, std::ostream& err) {
  cdds::Participant participant({.name = "concert_nav", .domain_id = dds.domain_id()});
  cdds::Reader<msg::NavVehicle> vehicles(participant, cdds::topics::nav_vehicle);
  cdds::Reader<msg::NavLocalisation> localisations(participant, cdds::topics::nav_localisation);
  cdds::Reader<msg::NavStatus> statuses(participant, cdds::topics::nav_status);
  cdds::Reader<msg::OccupancyGridMap> maps(participant, cdds::topics::nav_map);
  const auto wait = dds.timeout();
  const auto vehicle = vehicles.wait(wait);
  if (!vehicle) {
    err << "concert nav status: no nav service on domain " << participant.domain_id()
        << " (nothing on concert/nav/vehicle within " << dds.timeout_s << " s)\n";
    return 1;
  }
  const auto map = maps.wait(std::chrono::milliseconds(500));
  const auto loc = localisations.wait(std::chrono::milliseconds(1000));
  // The latest goal: the instance with the newest stamp among those delivered.
  std::optional<msg::NavStatus> latest;
  for (auto s = statuses.wait(std::chrono::milliseconds(300)); s; s = statuses.take()) {
    if (!latest || s->stamp_ns() > latest->stamp_ns()) latest = s;
  }
  if (dds.json) {
    nlohmann::ordered_json j;
    j["model_version"] = vehicle->model_version();
    j["drive"] = vehicle->drive();
    j["reason"] = vehicle->reason();
    j["lidars"] = vehicle->lidars();
    j["sonars"] = vehicle->sonars();
    j["imu"] = vehicle->imu();
    j["max_speed"] = vehicle->max_speed();
    if (map)
      j["map"] = {{"name", map->name()},
                  {"width", map->width()},
                  {"height", map->height()},
                  {"resolution", map->resolution()}};
    if (loc)
      j["localisation"] = {{"state", localisation_name(loc->state())},
                           {"pose", pose_json(loc->pose())}};
    if (latest) j["goal"] = status_json(*latest);
    out << j.dump() << std::endl;
    return 0;
  }
  out << "model version " << vehicle->model_version() << ": ";
  if (vehicle->drive().empty()) {
    out << "cannot navigate: " << vehicle->reason() << "\n";
  } else {
    out << vehicle->drive() << " drive, " << vehicle->footprint().size()
        << "-corner footprint, max " << vehicle->max_speed() << " m/s; lidars "
        << vehicle->lidars().size() << ", sonars " << vehicle->sonars().size() << ", imu "
        << (vehicle->imu().empty() ? "none" : vehicle->imu()) << "\n";
  }
  if (map) {
    out << "map '" << map->name() << "': " << map->width() << " x " << map->height() << " cells at "
        << map->resolution() << " m\n";
  } else {
    out << "map: none\n";
  }
  if (loc)
    out << "localisation: " << localisation_name(loc->state()) << " at " << pose_text(loc->pose())
        << "\n";
  if (latest) {
    out << "goal " << latest->request_id() << ": " << state_name(latest->state()) << " "
        << pose_text(latest->goal());
    if (!latest->reason().empty()) out << ": " << latest->reason();
    out << "\n";
  } else {
    out << "goal: none\n";
  }
  return 0;
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& nav =
      concert.group(concert.app(), "nav", "navigation of the mobile base (nav service)");
  {
    auto o = std::make_shared<GotoOptions>();
    CLI::App& verb =
        concert.verb(nav, "goto", "drive to a map pose, or in front of a BIM wall",
                     [&concert, o] { return run_goto(*o, concert.out(), concert.err()); });
    verb.add_option("POSE", o->pose, "goal in the map frame: x [m], y [m], heading [rad]")
        ->expected(3)
        ->type_name("X Y THETA")
        ->check(cli::real());
    verb.add_option("--wall", o->wall, "stand in front of this wall (its IFC GlobalId)")
        ->type_name("GLOBALID");
    verb.add_option("--at", o->at,
                    "with --wall: distance along the wall from its start, height [m]")
        ->expected(2)
        ->type_name("S H")
        ->check(cli::real());
    verb.add_option("--request-id", o->request_id, "the goal's id (default: random)")
        ->type_name("N")
        ->check(cli::number(1, 4294967295.0, true));
    verb.add_flag("--no-wait", o->no_wait, "send the goal and return");
    concert.add_dds_options(verb, o->dds, 300.0, "how long to follow the goal");
  }
  {
    auto id = std::make_shared<uint32_t>(0);
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb = concert.verb(nav, "cancel", "cancel a navigation goal", [&concert, id, dds] {
      return run_cancel(*id, *dds, concert.out(), concert.err());
    });
    verb.add_option("--request-id", *id, "the goal to cancel (default: whatever runs)")
        ->type_name("N")
        ->check(cli::number(0, 4294967295.0, true));
    concert.add_dds_options(verb, *dds, 5.0, "how long to wait for the nav service");
  }
  {
    auto o = std::make_shared<InitOptions>();
    CLI::App& verb =
        concert.verb(nav, "init", "(re)start localisation from a pose in the map",
                     [&concert, o] { return run_init(*o, concert.out(), concert.err()); });
    verb.add_option("POSE", o->pose, "the robot's pose in the map: x [m], y [m], heading [rad]")
        ->expected(3)
        ->required()
        ->type_name("X Y THETA")
        ->check(cli::real());
    verb.add_option("--std-xy", o->std_xy, "spread of the guess [m] (default: the service's)")
        ->check(cli::number(0.0));
    verb.add_option("--std-yaw", o->std_yaw, "spread of the heading [rad] (default: the service's)")
        ->check(cli::number(0.0));
    concert.add_dds_options(verb, o->dds, 5.0, "how long to wait for the nav service");
  }
  {
    auto dds = std::make_shared<cli::DdsOptions>();
    CLI::App& verb =
        concert.verb(nav, "status", "vehicle set-up, map, localisation and the latest goal",
                     [&concert, dds] { return run_status(*dds, concert.out(), concert.err()); });
    concert.add_dds_options(verb, *dds, 3.0, "how long to wait for the nav service");
  }
}

}  // namespace concert::nav
