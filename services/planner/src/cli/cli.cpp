// `concert plan drill` sends drilling-area goals to the planner service and follows them;
// `concert plan home` moves the arm to its homing posture (the transport posture nav drives with);
// `concert plan posture J2_E=0.65 ...` moves named arm joints to given positions (a task's start).

#include "planner/cli.hpp"

#include <charconv>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "dds/planner_node.hpp"

namespace concert::planner {
namespace {

/// What `concert plan drill`, `home` and `posture` send.
struct PlanOptions {
  std::string verb = "drill";
  bool home = false;                    ///< the arm home instead of goals
  std::vector<std::string> posture;     ///< NAME=POSITION: these joints instead of goals
  bool plan_only = false;               ///< home, posture: plan without executing
  std::vector<std::vector<double>> at;  ///< goals, 3 numbers each [m]
  std::vector<double> normal{-1.0, 0.0, 0.0};
  bool execute = false;
  std::string end_effector;
  uint32_t request_id = std::random_device{}() & 0x7fffffffu;
  cli::DdsOptions dds;
};

/// "J2_E=0.65" as a name and a position; a usage error naming the word otherwise.
std::pair<std::string, double> joint_position(const std::string& word) {
  const std::size_t eq = word.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == word.size())
    throw cli::UsageError("'" + word + "': a joint's position is NAME=POSITION, e.g. J2_E=0.65");
  const std::string value = word.substr(eq + 1);
  double v = 0.0;
  const auto r = std::from_chars(value.data(), value.data() + value.size(), v);  // as cli::number: no locale
  if (r.ec != std::errc() || r.ptr != value.data() + value.size() || !std::isfinite(v))
    throw cli::UsageError("'" + word + "': '" + value + "' is not a number (rad, or m for a prismatic joint)");
  return {word.substr(0, eq), v};
}

const char* state_name(msg::PlanState s) {
  switch (s) {
    case msg::PLAN_PLANNING: return "planning";
    case msg::PLAN_PLANNED: return "planned";
    case msg::PLAN_EXECUTING: return "executing";
    case msg::PLAN_SUCCEEDED: return "succeeded";
    case msg::PLAN_FAILED: return "failed";
  }
  return "?";
}

int send_request(const PlanOptions& o, std::ostream& out, std::ostream& err) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : o.at) points.emplace_back(p[0], p[1], p[2]);
  const Eigen::Vector3d normal(o.normal[0], o.normal[1], o.normal[2]);
  if (normal.norm() < 1e-9) throw cli::UsageError("--normal: must not be zero");
  std::vector<std::pair<std::string, double>> posture;
  for (const std::string& word : o.posture) posture.push_back(joint_position(word));
  const bool execute = o.home || !posture.empty() ? !o.plan_only : o.execute;
  const std::string who = "concert plan " + o.verb;
  const std::string& end_effector = o.end_effector;
  const double timeout_s = o.dds.timeout_s;
  const uint32_t request_id = o.request_id;
  try {
    concert::dds::Participant participant({.name = "concert_plan", .domain_id = o.dds.domain_id()});
    concert::dds::Reader<msg::RobotModel> models(participant, concert::dds::topics::robot_model);
    concert::dds::Reader<msg::PlanResult> results(participant, concert::dds::topics::plan_result);
    concert::dds::Writer<msg::PlanRequest> requests(participant, concert::dds::topics::plan_request);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000));
    const auto left = [&] {
      return std::max(std::chrono::milliseconds(0),
                      std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()));
    };
    const auto model = models.wait(std::min(left(), std::chrono::milliseconds(5000)));
    if (!model) {
      err << who << ": no robot model on domain " << participant.domain_id() << " (is concert_modelgen running?)\n";
      return 1;
    }
    if (!requests.wait_for_readers(1, std::min(left(), std::chrono::milliseconds(5000)))) {
      err << who << ": no planner listening on domain " << participant.domain_id() << " (is concert_planner running?)\n";
      return 1;
    }
    // The answer's path matched before the question is asked: a result written before our reader
    // matched the planner's writer would reach us only through the late joiner's history.
    if (!results.wait_for_writers(1, std::min(left(), std::chrono::milliseconds(5000)))) {
      err << who << ": the planner's results do not reach this client on domain " << participant.domain_id() << "\n";
      return 1;
    }
    msg::PlanRequest req;
    req.request_id(request_id);
    req.model_version(model->version());
    req.source("concert plan");
    req.end_effector(end_effector);
    req.execute(execute);
    req.arm_home(o.home);
    for (const auto& [name, position] : posture) {
      req.posture_names().push_back(name);
      req.posture_position().push_back(position);
    }
    const Eigen::Vector3d z = normal.normalized();
    const Eigen::Vector3d up = std::abs(z.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
    frame.linear().col(2) = z;
    frame.linear().col(0) = (up - up.dot(z) * z).normalized();
    frame.linear().col(1) = z.cross(frame.linear().col(0));
    for (const Eigen::Vector3d& p : points) {
      frame.translation() = p;
      req.goals().push_back(dds::to_msg(frame));
    }
    req.stamp_ns(now_ns());
    requests.write(req);
    if (o.dds.json) {
      out << nlohmann::ordered_json{{"request_id", request_id},
                                    {"goals", points.size()},
                                    {"home", o.home},
                                    {"posture", o.posture},
                                    {"model_version", model->version()},
                                    {"execute", execute}}
                 .dump()
          << std::endl;
    } else {
      out << "request " << request_id << ": "
          << (o.home              ? std::string("the arm home")
              : !posture.empty() ? "the arm to " + std::to_string(posture.size()) + " joint position(s)"
                                 : std::to_string(points.size()) + " goal(s)")
          << " for model version " << model->version() << (execute ? ", executing" : ", planning only") << "\n";
    }
    // Execution progress arrives many times a second: one line per 10 % of each goal.
    long printed_goal = -1;
    long printed_percent = 0;
    // The request is volatile: written before the planner's reader matched this writer (the
    // match is seen from this side first), it is lost. Until the planner acknowledges it
    // (PLAN_PLANNING, or any later answer) it is sent again every second, same id (the planner
    // takes a source's id once).
    constexpr auto kResend = std::chrono::milliseconds(1000);
    bool acknowledged = false;
    auto sent = std::chrono::steady_clock::now();
    while (left().count() > 0) {
      if (!acknowledged && std::chrono::steady_clock::now() - sent >= kResend) {
        req.stamp_ns(now_ns());
        requests.write(req);
        sent = std::chrono::steady_clock::now();
      }
      const auto r = results.wait(acknowledged ? left() : std::min(left(), kResend));
      if (!r || r->request_id() != request_id) continue;
      acknowledged = true;
      if (r->state() == msg::PLAN_EXECUTING) {
        const long percent = std::lround(100.0 * r->progress());
        const auto goal = static_cast<long>(r->goal_index());
        if (goal == printed_goal && percent < printed_percent + 10) continue;
        printed_goal = goal;
        printed_percent = percent - percent % 10;
      }
      if (o.dds.json) {
        nlohmann::ordered_json j = {
            {"request_id", r->request_id()}, {"goal", r->goal_index() + 1},
            {"goals", r->goal_count()},      {"state", state_name(r->state())},
            {"progress", r->progress()},     {"reason", r->reason()}};
        if (r->state() == msg::PLAN_PLANNED && !r->trajectory().empty()) {
          j["planning_time_s"] = r->planning_time();
          j["samples"] = r->trajectory().size();
          j["duration_s"] = r->trajectory().back().time();
        }
        out << j.dump() << std::endl;
      } else {
        out << "  goal " << r->goal_index() + 1 << "/" << r->goal_count() << " "
            << state_name(r->state());
        if (r->state() == msg::PLAN_PLANNED && !r->trajectory().empty()) {
          out << std::fixed << std::setprecision(1) << " in " << 1e3 * r->planning_time() << " ms, "
              << r->trajectory().size() << " samples, " << r->trajectory().back().time() << " s"
              << std::defaultfloat;
        }
        if (r->state() == msg::PLAN_EXECUTING)
          out << " " << std::lround(100.0 * r->progress()) << " %";
        if (!r->reason().empty()) out << ": " << r->reason();
        out << "\n";
      }
      if (r->state() == msg::PLAN_SUCCEEDED) return 0;
      if (r->state() == msg::PLAN_FAILED) {
        err << who << ": " << r->reason() << "\n";
        return 1;
      }
    }
    err << who << ": no final result within " << timeout_s << " s\n";
    return 1;
  } catch (const cli::UsageError&) {
    throw;
  } catch (const std::exception& e) {
    err << "concert plan " << o.verb << ": " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

void register_verbs(cli::Cli& concert) {
  CLI::App& plan =
      concert.group(concert.app(), "plan", "whole-body planning requests to the planner service");
  auto o = std::make_shared<PlanOptions>();
  CLI::App& verb =
      concert.verb(plan, "drill", "plan (and with --execute run) the approach to drilling areas",
                   [&concert, o] { return send_request(*o, concert.out(), concert.err()); });
  verb.add_option("--at", o->at,
                  "a drilling-area centre in the world frame [m] (repeat for several goals)")
      ->type_size(3)
      ->type_name("X Y Z")
      ->required()
      ->check(cli::real());
  verb.add_option("--normal", o->normal, "outward normal of the drilled surface")
      ->expected(3)
      ->type_name("NX NY NZ")
      ->check(cli::real())
      ->default_str("-1 0 0");
  verb.add_flag("--execute", o->execute, "execute the planned motion on the robot");
  verb.add_option("--end-effector", o->end_effector,
                  "the tool end-effector (default: the planner's choice)")
      ->type_name("NAME");
  verb.add_option("--request-id", o->request_id, "the request's id (default: random)")
      ->type_name("N")
      ->check(cli::number(0, 4294967295.0, true));
  concert.add_dds_options(verb, o->dds, 30.0, "how long to follow the request");

  auto h = std::make_shared<PlanOptions>();
  h->verb = "home";
  h->home = true;
  CLI::App& home = concert.verb(
      plan, "home",
      "move the arm to its homing posture, the base standing (the transport posture nav drives "
      "with; planned collision free and within the drives)",
      [&concert, h] { return send_request(*h, concert.out(), concert.err()); });
  home.add_flag("--plan-only", h->plan_only, "plan the motion without executing it");
  home.add_option("--request-id", h->request_id, "the request's id (default: random)")
      ->type_name("N")
      ->check(cli::number(0, 4294967295.0, true));
  concert.add_dds_options(home, h->dds, 60.0, "how long to follow the request");

  auto p = std::make_shared<PlanOptions>();
  p->verb = "posture";
  CLI::App& posture = concert.verb(
      plan, "posture",
      "move arm joints to given positions, the others keeping theirs, the base standing (e.g. the "
      "carrying posture a transport starts from; planned collision free and within the drives)",
      [&concert, p] { return send_request(*p, concert.out(), concert.err()); });
  posture.add_option("joints", p->posture, "a joint and its position [rad, m], e.g. J2_E=0.65 (repeat)")
      ->type_name("NAME=POSITION")
      ->required();
  posture.add_flag("--plan-only", p->plan_only, "plan the motion without executing it");
  posture.add_option("--request-id", p->request_id, "the request's id (default: random)")
      ->type_name("N")
      ->check(cli::number(0, 4294967295.0, true));
  concert.add_dds_options(posture, p->dds, 60.0, "how long to follow the request");
}

}  // namespace concert::planner
