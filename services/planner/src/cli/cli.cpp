// `concert plan drill`: sends drilling-area goals to the planner service and follows them.

#include "planner/cli.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <random>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"
#include "dds/planner_node.hpp"

namespace concert::planner {
namespace {

constexpr const char* kUsage =
    "usage: concert plan drill --at X Y Z [--at X Y Z ...] [--normal NX NY NZ] [--execute] [--end-effector NAME] "
    "[--request-id N] [--timeout S]";

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

double parse_number(const std::string& text, const std::string& what) {
  size_t pos = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &pos);
  } catch (const std::exception&) {
    pos = 0;
  }
  if (pos == 0 || pos != text.size() || !std::isfinite(v)) throw std::invalid_argument(what + " '" + text + "': expected a number");
  return v;
}

}  // namespace

int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << kUsage << "\n";
    return args.empty() ? 2 : 0;
  }
  if (args[0] != "drill") {
    err << "concert plan: unknown verb '" << args[0] << "'\n" << kUsage << "\n";
    return 2;
  }
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d normal(-1.0, 0.0, 0.0);
  bool execute = false;
  std::string end_effector;
  double timeout_s = 30.0;
  uint32_t request_id = std::random_device{}() & 0x7fffffffu;
  try {
    auto vec = [&](size_t& i, const std::string& opt) {
      if (i + 3 >= args.size()) throw std::invalid_argument(opt + " needs 3 numbers");
      Eigen::Vector3d v;
      for (int k = 0; k < 3; ++k) v[k] = parse_number(args[++i], opt);
      return v;
    };
    for (size_t i = 1; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a == "--at") {
        points.push_back(vec(i, a));
      } else if (a == "--normal") {
        normal = vec(i, a);
        if (normal.norm() < 1e-9) throw std::invalid_argument("--normal: must not be zero");
      } else if (a == "--execute") {
        execute = true;
      } else if ((a == "--end-effector" || a == "--request-id" || a == "--timeout") && i + 1 < args.size()) {
        const std::string& v = args[++i];
        if (a == "--end-effector") end_effector = v;
        if (a == "--timeout") timeout_s = parse_number(v, a);
        if (a == "--request-id") request_id = static_cast<uint32_t>(parse_number(v, a));
        if (a == "--timeout" && !(timeout_s > 0.0)) throw std::invalid_argument("--timeout: must be > 0");
      } else {
        throw std::invalid_argument("unknown or incomplete argument '" + a + "'");
      }
    }
    if (points.empty()) throw std::invalid_argument("no goal: give at least one --at X Y Z");
  } catch (const std::exception& e) {
    err << "concert plan drill: " << e.what() << "\n" << kUsage << "\n";
    return 2;
  }
  try {
    concert::dds::Participant participant({.name = "concert_plan"});
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
      err << "concert plan drill: no robot model on domain " << participant.domain_id() << " (is concert_modelgen running?)\n";
      return 1;
    }
    if (!requests.wait_for_readers(1, std::min(left(), std::chrono::milliseconds(5000)))) {
      err << "concert plan drill: no planner listening on domain " << participant.domain_id() << " (is concert_planner running?)\n";
      return 1;
    }
    msg::PlanRequest req;
    req.request_id(request_id);
    req.model_version(model->version());
    req.source("concert plan");
    req.end_effector(end_effector);
    req.execute(execute);
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
    req.stamp_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
    requests.write(req);
    out << "request " << request_id << ": " << points.size() << " goal(s) for model version " << model->version()
        << (execute ? ", executing" : ", planning only") << "\n";
    // Execution progress arrives many times a second: one line per 10 % of each goal.
    long printed_goal = -1;
    long printed_percent = 0;
    while (left().count() > 0) {
      const auto r = results.wait(left());
      if (!r || r->request_id() != request_id) continue;
      if (r->state() == msg::PLAN_EXECUTING) {
        const long percent = std::lround(100.0 * r->progress());
        const auto goal = static_cast<long>(r->goal_index());
        if (goal == printed_goal && percent < printed_percent + 10) continue;
        printed_goal = goal;
        printed_percent = percent - percent % 10;
      }
      out << "  goal " << r->goal_index() + 1 << "/" << r->goal_count() << " " << state_name(r->state());
      if (r->state() == msg::PLAN_PLANNED && !r->trajectory().empty()) {
        out << std::fixed << std::setprecision(1) << " in " << 1e3 * r->planning_time() << " ms, " << r->trajectory().size()
            << " samples, " << r->trajectory().back().time() << " s" << std::defaultfloat;
      }
      if (r->state() == msg::PLAN_EXECUTING) out << " " << std::lround(100.0 * r->progress()) << " %";
      if (!r->reason().empty()) out << ": " << r->reason();
      out << "\n";
      if (r->state() == msg::PLAN_SUCCEEDED) return 0;
      if (r->state() == msg::PLAN_FAILED) {
        err << "concert plan drill: " << r->reason() << "\n";
        return 1;
      }
    }
    err << "concert plan drill: no final result within " << timeout_s << " s\n";
    return 1;
  } catch (const std::exception& e) {
    err << "concert plan drill: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace concert::planner
