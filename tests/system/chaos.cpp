#include "chaos.hpp"

#include <signal.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <regex>
#include <sstream>
#include <thread>

#include "concert/common/clock.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/model/dds/pose.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "helpers.hpp"
#include "process.hpp"

namespace concert::system_test::chaos {

using namespace std::chrono_literals;

const std::vector<std::string>& services() {
  static const std::vector<std::string> all = {"safety", "discovery", "modelgen", "robot",         "planner",
                                               "nav",    "drill",     "collab",   "surface_finish"};
  return all;
}

bool watched(const std::string& service) {
  return service == "robot" || service == "planner" || service == "nav" || service == "drill" ||
         service == "collab" || service == "surface_finish";
}

namespace {

/// How far the robot may move while it holds: the hold controller settling after a stop in
/// the middle of an approach (measured up to 0.021 rad on a joint, 0.7 mm at the base). A robot
/// that kept going moves far more: the approaches move joints by about 1 rad, the base by
/// metres, over the hold watched (>= 1.5 s).
constexpr double kHoldBaseTolerance = 0.02;   // [m]
constexpr double kHoldJointTolerance = 0.05;  // [rad]
/// Heartbeats come every 200 ms: a service whose statuses this harness heard with a gap this
/// long (2.5 periods) before the safety service called it silent was starved on the wire; the
/// safety service's own starvation makes up the rest of its 1 s bound. A safety service that
/// misjudges a service beating on time sees no such gap here (0.2 s).
constexpr double kStarvedGap = 0.5;  // [s]
/// After a stop is seen, the robot has this long to come to rest before the hold is watched.
constexpr auto kHoldSettle = 500ms;
/// Without a kill of a watched service, no stop may come this long after the services are back
/// (the liveliness bound, 1 s, plus a margin).
constexpr auto kNoStopWatch = 2000ms;
/// The two drilling areas of the task, 1.2 m and 1.0 m high on the demo wall (x = 2.2 m).
const Eigen::Vector3d kAreas[2] = {{2.0, 0.0, 1.2}, {2.0, 0.4, 1.0}};
/// A request's final answer: planning and the approach (the first from the start pose takes
/// about 15 s), or the planner's own bound on the robot's silence.
constexpr auto kAnswerBound = 120s;
/// The planner publishes PLANNING as soon as it takes a request. Sent again every kResendAfter
/// meanwhile, a request still not taken within this generous bound never reached it (lost).
constexpr auto kAckBound = 30s;
constexpr auto kResendAfter = 1s;  // an unacknowledged request is sent again after this
/// A request taken later than this is reported (TaskReport::acknowledged_late): a latency
/// figure of the stack under the kills, not a loss.
constexpr auto kAckReported = 3s;
/// An operator's reset not answered within this bound (neither RUNNING nor a refusal) is lost.
constexpr auto kResetAnswer = 1s;

struct StatusSeen {
  Clock::time_point received;
  int64_t stamp_ns = 0;
  msg::ServiceState state = msg::SERVICE_STARTING;
  uint32_t version = 0;
  std::string hash;
  std::string message;
};

struct SafetySeen {
  Clock::time_point received;
  int64_t stamp_ns = 0;
  bool stopped = false;
  std::vector<std::string> causes;
};

struct KillSeen {
  std::string service;
  Clock::time_point at;
  int64_t at_ns = 0;
  std::optional<Clock::time_point> back;  // when it was ready again
};

struct Request {
  uint32_t id = 0;
  Clock::time_point sent;
  bool acknowledged = false;  // the planner published something for it
  std::optional<msg::PlanResult> final;
  bool probe = false;
  bool with_planner = false;  // unanswered: the planner was down while it waited for it
  msg::PlanRequest message;   // as sent (sent again, same id, while unacknowledged)
  Clock::time_point acknowledged_at{};  // when the planner's first answer to it came
};

std::string state_name(msg::ServiceState s) {
  switch (s) {
    case msg::SERVICE_STARTING:
      return "starting";
    case msg::SERVICE_READY:
      return "ready";
    case msg::SERVICE_RECONFIGURING:
      return "reconfiguring";
    case msg::SERVICE_ERROR:
      return "error";
    case msg::SERVICE_STOPPED:
      return "stopped";
  }
  return "unknown";
}

std::string describe(const SafetySeen& s) {
  std::string text = s.stopped ? "STOPPED" : "RUNNING";
  for (std::size_t i = 0; i < s.causes.size(); ++i) text += (i == 0 ? ": " : "; ") + s.causes[i];
  return text;
}

std::string describe(const StatusSeen& s) {
  return state_name(s.state) + " at model " + std::to_string(s.version) + " (" +
         s.hash.substr(0, 19) + ", \"" + s.message + "\")";
}

std::string short_hash(const std::string& hash) { return hash.substr(0, 19); }

/// The machine's 1-minute load average (a silence stop of a service nobody killed is most
/// often a starved heartbeat: the figure says how loaded the machine was).
std::string load_average() {
  std::string first;
  std::ifstream("/proc/loadavg") >> first;
  return first.empty() ? "unknown" : first;
}

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string tail(const std::string& text, std::size_t lines) {
  std::size_t pos = text.size();
  for (std::size_t n = 0; n <= lines && pos > 0; ++n) {
    pos = text.rfind('\n', pos - 1);
    if (pos == std::string::npos) return text;
  }
  return text.substr(pos + 1);
}

msg::Pose drilling_area(const Eigen::Vector3d& at) {
  // The frame `concert plan drill --at` builds: z along the wall's outward normal (-x), x up.
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z(-1.0, 0.0, 0.0);
  frame.linear().col(2) = z;
  frame.linear().col(0) = Eigen::Vector3d::UnitZ();
  frame.linear().col(1) = z.cross(Eigen::Vector3d::UnitZ());
  frame.translation() = at;
  return model::dds::to_pose_msg(frame);
}

bool names(const std::vector<std::string>& causes, const std::string& service) {
  return std::any_of(causes.begin(), causes.end(), [&](const std::string& c) {
    return c.find(" " + service + "@") != std::string::npos;
  });
}

}  // namespace

struct Chaos::Impl {
  Options o;
  std::vector<std::string> env;
  std::unique_ptr<testing::Process> up;
  std::vector<std::string> started;  // services `concert up` started

  dds::Participant participant{{.name = "chaos"}};
  mutable std::mutex m;
  std::condition_variable changed;
  std::map<std::string, std::deque<StatusSeen>> statuses;  // by service (one host)
  std::deque<SafetySeen> safety;                           // every sample, newest last
  uint32_t model_version = 0;                              // the current model
  std::string model_hash;
  std::optional<topology::ModuleTree> tree;  // the current tree, and its version
  uint32_t tree_version = 0;
  std::string tree_went_back;  // set when a tree came with a lower version than the one before
  std::optional<std::pair<int64_t, Clock::time_point>> tree_seen;  // stamp, when
  std::optional<msg::SimTruth> truth;
  Clock::time_point truth_received{};
  Clock::time_point joints_received{};
  std::vector<double> joints;  // positions of the latest joint state at the current model
  std::vector<std::string> joint_names;  // and their names
  std::map<uint32_t, Request> requests;
  std::vector<KillSeen> kills;

  std::unique_ptr<dds::Reader<msg::ServiceStatus>> status_reader;
  std::unique_ptr<dds::Reader<msg::SafetyState>> safety_reader;
  std::unique_ptr<dds::Reader<msg::ModuleTree>> tree_reader;
  std::unique_ptr<dds::Reader<msg::SimTruth>> truth_reader;
  std::unique_ptr<dds::Reader<msg::JointState>> joint_reader;
  std::unique_ptr<dds::Reader<msg::PlanResult>> result_reader;
  dds::Writer<msg::PlanRequest> request_writer{participant, dds::topics::plan_request};
  dds::Writer<msg::SafetyReset> reset_writer{participant, dds::topics::safety_reset};

  std::atomic<bool> task_stop{false};
  std::optional<Clock::time_point> stopped_at;  // when the task stopped (under m)
  std::thread task;
  uint32_t next_id = 1;  // under m
  uint32_t resets = 0;

  explicit Impl(Options options) : o(std::move(options)), env{"XDG_RUNTIME_DIR=" + o.run_dir} {
    status_reader = std::make_unique<dds::Reader<msg::ServiceStatus>>(
        participant, dds::topics::status, [this](const msg::ServiceStatus& s, const auto&) {
          std::lock_guard lock(m);
          auto& seen = statuses[s.service()];
          seen.push_back({Clock::now(), s.stamp_ns(), s.state(), s.model_version(), s.model_hash(),
                          s.message()});
          if (seen.size() > 2000) seen.pop_front();
          changed.notify_all();
        });
    safety_reader = std::make_unique<dds::Reader<msg::SafetyState>>(
        participant, dds::topics::safety_state, [this](const msg::SafetyState& s, const auto&) {
          std::lock_guard lock(m);
          safety.push_back({Clock::now(),
                            s.stamp_ns(),
                            s.mode() == msg::SAFETY_STOPPED,
                            {s.causes().begin(), s.causes().end()}});
          if (safety.size() > 20000) safety.pop_front();
          changed.notify_all();
        });
    tree_reader = std::make_unique<dds::Reader<msg::ModuleTree>>(
        participant, dds::topics::module_tree, [this](const msg::ModuleTree& t, const auto&) {
          std::lock_guard lock(m);
          tree = topology::dds::to_core(t);
          if (t.version() < tree_version)
            tree_went_back = "the module tree's version went back from " +
                             std::to_string(tree_version) + " to " + std::to_string(t.version());
          tree_version = t.version();
          tree_seen = {t.stamp_ns(), Clock::now()};
          changed.notify_all();
        });
    truth_reader = std::make_unique<dds::Reader<msg::SimTruth>>(
        participant, dds::topics::sim_truth, [this](const msg::SimTruth& t, const auto&) {
          std::lock_guard lock(m);
          truth = t;
          truth_received = Clock::now();
        });
    joint_reader = std::make_unique<dds::Reader<msg::JointState>>(
        participant, dds::topics::joint_state, [this](const msg::JointState& j, const auto&) {
          std::lock_guard lock(m);
          if (j.model_version() != model_version) return;
          joints = j.position();
          joint_names = j.name();
          joints_received = Clock::now();
        });
    result_reader = std::make_unique<dds::Reader<msg::PlanResult>>(
        participant, dds::topics::plan_result, [this](const msg::PlanResult& r, const auto&) {
          std::lock_guard lock(m);
          const auto it = requests.find(r.request_id());
          if (it == requests.end() || it->second.final) return;
          if (!it->second.acknowledged) it->second.acknowledged_at = Clock::now();
          it->second.acknowledged = true;
          if (r.state() == msg::PLAN_SUCCEEDED || r.state() == msg::PLAN_FAILED)
            it->second.final = r;
          changed.notify_all();
        });
  }

  ~Impl() {
    task_stop = true;
    if (task.joinable()) task.join();
    if (up) up->stop(30s);
  }

  // ---- the stack ------------------------------------------------------------------------

  std::string up_log() const { return up ? up->out() + up->err() : ""; }

  pid_t pid_of(const std::string& service) const {
    const std::string log = up_log();
    const std::regex line("started " + service + " \\(pid ([0-9]+)\\)");
    pid_t pid = -1;
    for (auto it = std::sregex_iterator(log.begin(), log.end(), line); it != std::sregex_iterator();
         ++it) {
      pid = std::stoi((*it)[1]);
    }
    return pid;
  }

  std::string logs() const {
    std::string text = "\n--- concert up:\n" + tail(up_log(), 40);
    const char* domain = std::getenv("CONCERT_DOMAIN_ID");
    const std::string dir = o.run_dir + "/concert-d" + (domain ? domain : "0") + "/logs/";
    for (const auto& s : started)
      text += "--- " + s + ".log:\n" + tail(read_text(dir + s + ".log"), s == "safety" ? 60 : 12);
    return text;
  }

  /// Waits (bounded) for `done`, which is called with m held; false on timeout.
  template <class F>
  bool wait_until(Clock::time_point deadline, F done) {
    std::unique_lock lock(m);
    while (!done()) {
      if (Clock::now() >= deadline) return false;
      changed.wait_for(lock, 20ms);
    }
    return true;
  }

  std::optional<StatusSeen> last_status(const std::string& service) const {
    const auto it = statuses.find(service);
    if (it == statuses.end() || it->second.empty()) return std::nullopt;
    return it->second.back();
  }

  /// Ready at the current model: READY, same version and hash (discovery reports none: READY).
  bool ready_at_model(const std::string& service, const StatusSeen& s) const {
    if (s.state != msg::SERVICE_READY) return false;
    return service == "discovery" || (s.version == model_version && s.hash == model_hash);
  }

  /// The first status of `service` stamped after `after_ns` that is ready at the current model.
  std::optional<StatusSeen> ready_after(const std::string& service, int64_t after_ns) const {
    const auto it = statuses.find(service);
    if (it == statuses.end()) return std::nullopt;
    for (const auto& s : it->second) {
      if (s.stamp_ns > after_ns && ready_at_model(service, s)) return s;
    }
    return std::nullopt;
  }

  bool all_ready() const {
    return std::all_of(started.begin(), started.end(), [&](const std::string& s) {
      const auto last = last_status(s);
      return last && ready_at_model(s, *last);
    });
  }

  /// The model every service runs once they agree: modelgen's, when everyone else reports it.
  bool agree_on_model(uint32_t at_least) {
    const auto mg = last_status("modelgen");
    if (!mg || mg->state != msg::SERVICE_READY || mg->version < at_least || mg->hash.empty())
      return false;
    model_version = mg->version;
    model_hash = mg->hash;
    return all_ready() && tree.has_value();
  }

  std::optional<SafetySeen> safety_now() const {
    if (safety.empty()) return std::nullopt;
    return safety.back();
  }

  std::vector<std::string> start() {
    up = std::make_unique<testing::Process>(
        dies_with_test({CONCERT_BIN, "up", "--assembly", o.assembly, "--world", o.world}), env);
    const auto deadline = Clock::now() + o.up_timeout;
    // Which services `concert up` started: it starts them all at once, the required four first,
    // having said which are not built (bounded wait until it named each one way or the other).
    const auto all_named = [&] {
      const std::string log = up_log();
      return std::all_of(services().begin(), services().end(), [&](const std::string& s) {
        return pid_of(s) > 0 || log.find("running without " + s + "\n") != std::string::npos;
      });
    };
    while (Clock::now() < deadline && up->running() && !all_named())
      std::this_thread::sleep_for(50ms);
    for (const auto& s : services())
      if (pid_of(s) > 0) started.push_back(s);
    if (started.size() < 4) return {"concert up did not start the stack" + logs()};
    if (!wait_until(deadline, [&] { return agree_on_model(1); })) {
      return {"the stack did not come up at one model within " +
              std::to_string(o.up_timeout.count()) + " s" + status_table() + logs()};
    }
    if (!o.swap_to.empty()) {
      const uint32_t before = model_version;
      const auto swap =
          testing::run(dies_with_test({CONCERT_BIN, "sim", "swap", o.swap_to}), 60s, env);
      if (swap.code != 0) return {"concert sim swap failed: " + swap.err + logs()};
      if (!wait_until(deadline, [&] { return agree_on_model(before + 1); })) {
        return {"the services did not agree on the swapped model" + status_table() + logs()};
      }
    }
    if (!wait_until(deadline, [&] { return safety_now() && !safety_now()->stopped; })) {
      std::lock_guard lock(m);
      return {"the safety state is not RUNNING: " +
              (safety.empty() ? std::string("none") : describe(safety.back())) + logs()};
    }
    task = std::thread([this] { run_task(); });
    return {};
  }

  std::string status_table() const {
    std::lock_guard lock(m);
    std::string text = "\nstatuses:";
    for (const auto& s : started) {
      const auto last = last_status(s);
      text += "\n  " + s + ": " + (last ? describe(*last) : "never heard");
    }
    return text;
  }

  // ---- the task -------------------------------------------------------------------------

  /// Sends a drilling approach to area `area` (executed); returns its id.
  uint32_t send(int area, bool probe) {
    msg::PlanRequest req;
    {
      std::lock_guard lock(m);
      req.request_id(next_id++);
      req.model_version(model_version);
      requests[req.request_id()] = {req.request_id(), Clock::now(), false, std::nullopt, probe};
    }
    req.stamp_ns(now_ns());
    req.source(probe ? "chaos probe" : "chaos task");
    req.execute(true);
    req.goals().push_back(drilling_area(kAreas[area]));
    {
      std::lock_guard lock(m);
      requests[req.request_id()].message = req;
    }
    request_writer.write(req);
    return req.request_id();
  }

  /// Waits until the planner took request `id` (or was down, or the task stopped): false when
  /// it did not within kAckBound. Unacknowledged, the request is sent again every kResendAfter
  /// as the drill does (a request written before this writer matched a restarted planner's
  /// reader is lost: PlanRequest is volatile).
  bool taken(uint32_t id) {
    const auto sent = [&] {
      std::lock_guard lock(m);
      return requests.at(id).sent;
    }();
    const auto gone = [&] { return task_stop || down_between("planner", sent, Clock::now()); };
    for (auto slice = sent + kResendAfter;; slice += kResendAfter) {
      const auto until = std::min(slice, sent + kAckBound);
      if (wait_until(until, [&] { return requests.at(id).acknowledged || gone(); })) return true;
      if (until >= sent + kAckBound) return false;
      msg::PlanRequest again;
      {
        std::lock_guard lock(m);
        again = requests.at(id).message;
      }
      request_writer.write(again);
    }
  }

  /// Waits for the final answer to request `id`: it must be taken within kAckBound, and
  /// answered within `bound`. Gives up on a request the planner was killed holding (it is lost
  /// with it) and on one never taken (lost).
  std::optional<msg::PlanResult> answer(uint32_t id, Clock::duration bound) {
    std::optional<msg::PlanResult> result;
    const auto sent = [&] {
      std::lock_guard lock(m);
      return requests.at(id).sent;
    }();
    const auto gone = [&] { return task_stop || down_between("planner", sent, Clock::now()); };
    if (taken(id)) {
      wait_until(sent + bound, [&] {
        result = requests.at(id).final;
        return result.has_value() || gone();
      });
    }
    std::lock_guard lock(m);
    if (!result && down_between("planner", sent, Clock::now())) requests.at(id).with_planner = true;
    return result;
  }

  void run_task() {
    int area = 0;
    while (!task_stop) {
      // Only while the robot may move and the planner runs the current model.
      const bool go = [&] {
        std::lock_guard lock(m);
        const auto s = safety_now();
        const auto planner = last_status("planner");
        return s && !s->stopped && planner && ready_at_model("planner", *planner) &&
               !down_between("planner", Clock::now(), Clock::now());
      }();
      if (!go) {
        std::this_thread::sleep_for(50ms);
        continue;
      }
      const uint32_t id = send(area, false);
      const auto result = answer(id, kAnswerBound);
      if (result && result->state() == msg::PLAN_SUCCEEDED) area = 1 - area;
      std::this_thread::sleep_for(100ms);
    }
  }

  /// Whether `service` was down (killed, not yet ready again) at some time in [from, to]. A
  /// request sent to a planner that is down is lost with it, like one it was killed holding.
  bool down_between(const std::string& service, Clock::time_point from,
                    Clock::time_point to) const {
    return std::any_of(kills.begin(), kills.end(), [&](const KillSeen& k) {
      return k.service == service && k.at <= to && (!k.back || *k.back >= from);
    });
  }

  TaskReport task_report() const {
    std::lock_guard lock(m);
    TaskReport r;
    for (const auto& [id, q] : requests) {
      if (q.probe) continue;
      ++r.sent;
      if (q.acknowledged) {
        const double took = seconds(q.acknowledged_at - q.sent);
        r.slowest_ack_s = std::max(r.slowest_ack_s, took);
        if (q.acknowledged_at - q.sent > kAckReported) ++r.acknowledged_late;
      }
      const std::string head = "request " + std::to_string(id) + " (" +
                               std::to_string(seconds(q.sent - requests.begin()->second.sent)) +
                               " s): ";
      if (!q.final && q.with_planner) {
        ++r.lost_with_planner;
        r.details.push_back(head + "lost with the killed planner");
      } else if (!q.final && stopped_at &&
                 *stopped_at - q.sent <
                     (q.acknowledged ? Clock::duration(kAnswerBound) : kAckBound)) {
        r.details.push_back(head + "in flight when the task stopped");
      } else if (!q.final) {
        ++r.lost;
        r.details.push_back(head + (q.acknowledged ? "LOST: taken, never answered"
                                                   : "LOST: never taken by the planner"));
      } else if (q.final->state() == msg::PLAN_SUCCEEDED) {
        ++r.succeeded;
      } else if (q.final->reason().find("safety stop") != std::string::npos) {
        ++r.failed_safety_stop;
        r.details.push_back(head + "failed: " + q.final->reason());
      } else {
        ++r.failed_other;
        r.details.push_back(head + "failed: " + q.final->reason());
      }
    }
    return r;
  }

  // ---- rounds ---------------------------------------------------------------------------

  /// The largest gap between `service`'s statuses as this harness received them in the 3 s
  /// before `until` (up to `until`) [s]. Called with m held.
  double heard_gap(const std::string& service, Clock::time_point until) const {
    const auto it = statuses.find(service);
    if (it == statuses.end()) return seconds(3s);
    Clock::time_point last = until - 3s;
    double gap = 0.0;
    for (const auto& st : it->second) {
      if (st.received < last || st.received > until) continue;
      gap = std::max(gap, seconds(st.received - last));
      last = st.received;
    }
    return std::max(gap, seconds(until - last));
  }

  /// A stop cause naming a service nobody killed: starved (true) when it says the service went
  /// silent and this harness heard its heartbeats go quiet too (>= kStarvedGap: the machine
  /// starved it, the stop was right), else a false stop; with the text describing it.
  /// `context` goes into the text. Called with `m` held.
  std::pair<bool, std::string> judge_cause(const std::string& c, Clock::time_point seen,
                                           const std::string& context) const {
    static const std::regex silent("^liveliness: ([a-z_]+)@\\S+ silent for");
    std::smatch who;
    const double gap = std::regex_search(c, who, silent) ? heard_gap(who[1], seen) : 0.0;
    std::ostringstream text;
    text << std::fixed << std::setprecision(2) << "\"" << c << "\" (" << context
         << "; load average " << load_average() << "; its heartbeats heard here: largest gap "
         << gap << " s)";
    return {gap >= kStarvedGap, text.str()};
  }

  /// Base pose and joint positions now (from the simulator's truth and the joint state).
  std::pair<Eigen::Vector2d, std::vector<double>> pose_now() const {
    std::lock_guard lock(m);
    return {truth ? Eigen::Vector2d(truth->x(), truth->y()) : Eigen::Vector2d::Zero(), joints};
  }

  RoundReport round(const std::vector<Kill>& kills_asked) {
    RoundReport r;
    r.kills = kills_asked;
    std::sort(r.kills.begin(), r.kills.end(),
              [](const Kill& a, const Kill& b) { return a.after < b.after; });
    auto fail = [&](const std::string& text) { r.failures.push_back(text); };
    const auto t0 = Clock::now();
    std::map<std::string, int64_t> killed_at_ns;
    std::map<std::string, Clock::time_point> killed_at;
    std::optional<SafetySeen> safety_before_kill;  // of a safety kill
    bool stopped_before = false;
    {
      std::lock_guard lock(m);
      stopped_before = safety_now() && safety_now()->stopped;
    }
    for (const Kill& k : r.kills) {
      std::this_thread::sleep_until(t0 + k.after);
      const pid_t pid = pid_of(k.service);
      std::lock_guard lock(m);
      if (k.service == "safety") safety_before_kill = safety_now();
      if (pid <= 0 || ::kill(pid, SIGKILL) != 0) {
        fail(k.service + " was not running when it was to be killed (pid " + std::to_string(pid) +
             ")");
        continue;
      }
      killed_at_ns[k.service] = now_ns();
      killed_at[k.service] = Clock::now();
      kills.push_back({k.service, killed_at[k.service], killed_at_ns[k.service]});
    }

    // 1. Every killed service comes back, ready at the current model.
    Clock::time_point all_back = Clock::now();
    for (const auto& [service, at_ns] : killed_at_ns) {
      const auto deadline = killed_at[service] + o.ready_timeout;
      std::optional<StatusSeen> ready;
      const bool back = wait_until(deadline, [&] {
        ready = ready_after(service, at_ns);
        if (service == "discovery" && ready)
          return tree_seen && tree_seen->first > at_ns;  // and its tree is on the wire again
        return ready.has_value();
      });
      std::lock_guard lock(m);
      if (!back) {
        const auto last = last_status(service);
        fail(service + " did not come back ready at model " + std::to_string(model_version) + " (" +
             short_hash(model_hash) + ") within " + std::to_string(o.ready_timeout.count()) +
             " s of its kill: last status " + (last ? describe(*last) : "none") +
             (last && last->stamp_ns <= at_ns ? " (from before the kill)" : ""));
        continue;
      }
      const auto when =
          service == "discovery" ? std::max(ready->received, tree_seen->second) : ready->received;
      r.kill_to_ready_s[service] = seconds(when - killed_at[service]);
      for (auto& k : kills)
        if (k.service == service && k.at_ns == at_ns) k.back = when;
      all_back = std::max(all_back, when);
    }

    // 2. A killed watched service stops the robot, naming it; nothing else stops it.
    std::vector<std::string> expected;
    for (const auto& [service, at] : killed_at)
      if (watched(service)) expected.push_back(service);
    const auto stop_deadline = all_back + (expected.empty() ? kNoStopWatch : o.stop_timeout);
    Clock::time_point stop_seen{};
    if (!expected.empty()) {
      const bool named = wait_until(stop_deadline, [&] {
        const auto s = safety_now();
        if (!s || !s->stopped) return false;
        for (const auto& e : expected)
          if (!names(s->causes, e)) return false;
        stop_seen = s->received;
        return true;
      });
      if (!named) {
        std::lock_guard lock(m);
        std::string want;
        for (const auto& e : expected) want += (want.empty() ? "" : ", ") + e;
        fail("no safety stop naming " + want + " within " + std::to_string(o.stop_timeout.count()) +
             " s of it being back: the safety state is " +
             (safety.empty() ? std::string("unknown") : describe(safety.back())));
      }
    } else {
      std::this_thread::sleep_until(stop_deadline);
    }
    {
      std::lock_guard lock(m);
      std::map<std::string, Clock::time_point> first_seen;  // each cause
      for (const auto& s : safety) {
        if (s.received < t0 || !s.stopped) continue;
        r.stopped = true;
        for (const auto& c : s.causes) {
          if (first_seen.emplace(c, s.received).second) r.causes.push_back(c);
        }
      }
      if (stopped_before) r.causes.clear();  // a stop carried in from before: judged then
      std::string killed;
      for (const auto& x : r.kills) killed += (killed.empty() ? "" : ", ") + x.service;
      for (const auto& c : r.causes) {
        const bool explained = std::any_of(
            expected.begin(), expected.end(),
            [&](const std::string& e) { return c.find(" " + e + "@") != std::string::npos; });
        if (explained) continue;
        // A silence of a service nobody killed: the stop is right if its heartbeats really
        // went quiet on the wire (this harness, another reader, heard the same gap: the
        // machine starved it), false if they kept coming.
        const auto [starved, text] = judge_cause(c, first_seen[c], "killed: " + killed);
        if (starved) {
          r.starved.push_back(text);
        } else {
          fail("false stop: " + text);
        }
      }
    }

    // 3. The safety service comes back in the state it left.
    if (safety_before_kill) {
      const int64_t at_ns = killed_at_ns["safety"];
      const auto after_kill = [&](const SafetySeen& s) { return s.stamp_ns > at_ns; };
      // Its READY status can be heard before its first safety state: each topic's endpoints
      // are matched on their own (one run judged the state missing 0.8 s after the kill).
      wait_until(killed_at["safety"] + o.ready_timeout,
                 [&] { return std::any_of(safety.begin(), safety.end(), after_kill); });
      std::lock_guard lock(m);
      const auto first = std::find_if(safety.begin(), safety.end(), after_kill);
      if (first == safety.end()) {
        fail("the restarted safety service published no safety state within " +
             std::to_string(o.ready_timeout.count()) + " s of its kill");
      } else if (safety_before_kill->stopped) {
        for (const auto& c : safety_before_kill->causes) {
          if (!first->stopped ||
              std::find(first->causes.begin(), first->causes.end(), c) == first->causes.end())
            fail("the restarted safety service lost its latched stop: before the kill " +
                 describe(*safety_before_kill) + ", after " + describe(*first));
        }
      } else if (first->stopped && expected.empty()) {
        fail("the restarted safety service stopped the robot: before the kill " +
             describe(*safety_before_kill) + ", after " + describe(*first));
      }
    }

    // 4. While stopped, the robot holds and refuses commands; only a reset resumes it.
    const bool stopped_now = [&] {
      std::lock_guard lock(m);
      return safety_now() && safety_now()->stopped;
    }();
    if (stopped_now) hold_and_reset(r, std::max(stop_seen, all_back), t0);

    // 5. What a reader joining now gets: the same model, tree and safety state.
    check_wire(r);
    if (o.print) print(r);
    return r;
  }

  void hold_and_reset(RoundReport& r, Clock::time_point stopped_since, Clock::time_point t0) {
    auto fail = [&](const std::string& text) { r.failures.push_back(text); };
    std::this_thread::sleep_until(stopped_since + kHoldSettle);
    // The reference is what the robot says now: after a robot restart the last samples heard
    // can still be the killed simulator's (bounded wait for fresh ones; judged below).
    const auto fresh_after = Clock::now();
    wait_until(fresh_after + 5s,
               [&] { return truth_received > fresh_after && joints_received > fresh_after; });
    const auto hold_start = Clock::now();
    const auto reference = pose_now();
    auto watch = [&] {
      const auto now = pose_now();
      r.held_base_m = std::max(r.held_base_m, (now.first - reference.first).norm());
      for (std::size_t i = 0; i < std::min(now.second.size(), reference.second.size()); ++i) {
        const double moved = std::abs(now.second[i] - reference.second[i]);
        if (moved <= r.held_joint_rad) continue;
        r.held_joint_rad = moved;
        std::lock_guard lock(m);
        r.held_joint = i < joint_names.size() ? joint_names[i] : "joint " + std::to_string(i);
      }
    };
    // A command sent now is refused, naming the stop (sent again until the planner took it).
    const uint32_t probe = send(0, true);
    taken(probe);
    std::optional<msg::PlanResult> answer_to_probe;
    const auto probe_deadline = Clock::now() + 60s;
    while (Clock::now() < probe_deadline) {
      watch();
      {
        std::lock_guard lock(m);
        answer_to_probe = requests.at(probe).final;
      }
      if (answer_to_probe && Clock::now() - hold_start >= o.hold_watch) break;
      std::this_thread::sleep_for(20ms);
    }
    r.hold_s = seconds(Clock::now() - hold_start);
    if (!answer_to_probe) {
      fail("a plan request sent while stopped got no answer within 60 s");
    } else if (answer_to_probe->state() != msg::PLAN_FAILED ||
               answer_to_probe->reason().find("safety stop") == std::string::npos) {
      fail("a plan request sent while stopped was not refused naming the stop: " +
           std::string(answer_to_probe->state() == msg::PLAN_SUCCEEDED ? "succeeded" : "failed: ") +
           answer_to_probe->reason());
    }
    {
      // The hold is judged on what the simulator and the robot said while it was watched.
      std::lock_guard lock(m);
      if (truth_received < hold_start || joints_received < hold_start || reference.second.empty())
        fail("the hold could not be watched: no simulator truth or joint state at model " +
             std::to_string(model_version) + " heard while stopped");
    }
    if (r.held_base_m > kHoldBaseTolerance || r.held_joint_rad > kHoldJointTolerance) {
      std::ostringstream text;
      text << "the robot moved while stopped: base " << r.held_base_m << " m, a joint "
           << r.held_joint_rad << " rad (" << r.held_joint << ") over " << r.hold_s << " s";
      fail(text.str());
    }
    {
      std::lock_guard lock(m);
      // No RUNNING between the stop and the reset: the stop is latched.
      bool seen_stop = false;
      for (const auto& s : safety) {
        if (s.received < t0) continue;
        if (s.stopped) seen_stop = true;
        if (seen_stop && !s.stopped) {
          fail("the safety stop ended without a reset: " + describe(s));
          break;
        }
      }
      const auto& robot = statuses["robot"];
      const bool holding = std::any_of(robot.begin(), robot.end(), [&](const StatusSeen& s) {
        return s.received >= t0 && s.message.rfind("safety stop: holding", 0) == 0;
      });
      if (!holding) fail("the robot service never said it holds for the safety stop");
    }
    // The operator's reset; true once the safety service runs again after it.
    Clock::time_point released{};
    const auto press_reset = [&] {
      msg::SafetyReset reset;
      reset.request_id(++resets);
      reset.stamp_ns(now_ns());
      reset.source("chaos operator");
      reset.reason("round over");
      bool running = false;
      for (int attempt = 0; attempt < 5 && !running; ++attempt) {
        // A reset written to a restarted safety service's reader before it matched (the killed
        // one's still counts until its lease ends) is lost: the operator presses again.
        const auto written = Clock::now();
        reset_writer.write(reset);
        running = wait_until(written + kResetAnswer, [&] {
          const auto s = safety_now();
          if (!s || s->stopped || s->received <= written) return false;
          released = s->received;
          return true;
        });
        if (running) break;
        std::lock_guard lock(m);
        const auto& notes = statuses["safety"];
        const bool refused = std::any_of(notes.begin(), notes.end(), [&](const StatusSeen& n) {
          return n.received > written && n.message.find("reset by " + reset.source()) == 0 &&
                 n.message.find("refused") != std::string::npos;
        });
        if (refused) break;
        ++r.resets_lost;
      }
      if (!running) {
        const auto safety_status = [&] {
          std::lock_guard lock(m);
          const auto st = last_status("safety");
          return st ? st->message : std::string("none");
        }();
        fail("the operator reset did not release the stop within 5 s: safety says \"" +
             safety_status + "\"");
      }
      return running;
    };
    const auto reset_at = Clock::now();
    if (!press_reset()) return;
    // The task runs again: a request sent after the reset succeeds. A stop in between naming
    // only services whose heartbeats this harness also heard go quiet (the machine starved
    // them: the stop was right) is counted as starved and reset again, up to 3 times; any
    // other stop fails the round.
    const auto resumed = [&] {
      return std::any_of(requests.begin(), requests.end(), [&](const auto& q) {
        return !q.second.probe && q.second.sent > reset_at && q.second.final &&
               q.second.final->state() == msg::PLAN_SUCCEEDED;
      });
    };
    for (int again = 0;; ++again) {
      std::optional<SafetySeen> stop;
      const bool done = wait_until(released + o.resume_timeout, [&] {
        if (resumed()) return true;
        const auto st = safety_now();
        if (st && st->stopped && st->received > released) stop = st;
        return stop.has_value();
      });
      if (done && !stop) return;
      {
        std::lock_guard lock(m);
        if (stop) {
          std::vector<std::string> starved_now;
          std::string unexplained;
          for (const auto& c : stop->causes) {
            const auto [starved, text] = judge_cause(c, stop->received, "after the reset");
            if (starved) {
              starved_now.push_back(text);
            } else {
              unexplained += (unexplained.empty() ? "" : ", ") + text;
            }
          }
          if (!unexplained.empty()) {
            fail("false stop after the reset: " + unexplained);
            return;
          }
          r.starved.insert(r.starved.end(), starved_now.begin(), starved_now.end());
        }
        if (!stop || again >= 3) {
          std::string last = "none sent";
          for (const auto& [id, q] : requests) {
            if (q.sent > reset_at && !q.probe)
              last = "request " + std::to_string(id) +
                     (q.final ? (q.final->state() == msg::PLAN_SUCCEEDED
                                     ? " succeeded"
                                     : " failed: " + q.final->reason())
                              : " unanswered");
          }
          fail("the task did not run again within " + std::to_string(o.resume_timeout.count()) +
               " s of the reset" +
               (again > 0 ? " (reset " + std::to_string(again + 1) + " times)" : "") +
               " (last request: " + last + ")");
          return;
        }
      }
      if (!press_reset()) return;
    }
  }

  /// A fresh participant's readers get the latched model, tree and safety state.
  void check_wire(RoundReport& r) {
    auto fail = [&](const std::string& text) { r.failures.push_back(text); };
    dds::Participant late({.name = "chaos_late_joiner"});
    dds::Reader<msg::RobotModel> models(late, dds::topics::robot_model);
    dds::Reader<msg::ModuleTree> trees(late, dds::topics::module_tree);
    dds::Reader<msg::SafetyState> states(late, dds::topics::safety_state);
    const auto model = models.wait(5000ms);
    const auto tree_msg = trees.wait(5000ms);
    const auto state = states.wait(5000ms);
    std::lock_guard lock(m);
    if (!model) {
      fail("a reader joining after the round got no robot model within 5 s");
    } else if (model->version() != model_version || model->content_hash() != model_hash) {
      fail("a reader joining after the round got model " + std::to_string(model->version()) + " (" +
           short_hash(model->content_hash()) + "), the services run " +
           std::to_string(model_version) + " (" + short_hash(model_hash) + ")");
    }
    if (!tree_msg) {
      fail("a reader joining after the round got no module tree within 5 s");
    } else if (!(topology::dds::to_core(*tree_msg) == *tree)) {
      fail("a reader joining after the round got another module tree (version " +
           std::to_string(tree_msg->version()) + ")");
    }
    if (!tree_went_back.empty()) {
      fail(tree_went_back);
      tree_went_back.clear();
    }
    if (!state) {
      fail("a reader joining after the round got no safety state within 5 s");
    } else if (!safety.empty() &&
               ((state->mode() == msg::SAFETY_STOPPED) != safety.back().stopped)) {
      fail("a reader joining after the round got the safety state " +
           std::string(state->mode() == msg::SAFETY_STOPPED ? "STOPPED" : "RUNNING") +
           ", the robot has " + describe(safety.back()));
    }
  }

  void print(const RoundReport& r) const {
    std::ostringstream line;
    line << std::fixed << std::setprecision(2) << "chaos round: killed";
    for (const auto& k : r.kills) {
      line << " " << k.service;
      if (k.after.count() > 0) line << "@" << k.after.count() << "ms";
      const auto it = r.kill_to_ready_s.find(k.service);
      line << " (ready " << (it == r.kill_to_ready_s.end() ? std::string("never") : [&] {
        std::ostringstream s;
        s << std::fixed << std::setprecision(2) << it->second << " s";
        return s.str();
      }()) << ")";
    }
    if (r.stopped) {
      line << "; stopped:";
      for (const auto& c : r.causes) line << " [" << c << "]";
      line << "; held " << r.hold_s << " s (base " << r.held_base_m * 1e3 << " mm, joints "
           << r.held_joint_rad << " rad" << (r.held_joint.empty() ? "" : ", most " + r.held_joint) << ")";
    } else {
      line << "; no stop";
    }
    line << (r.failures.empty() ? "; ok" : "; FAILED");
    for (const auto& f : r.failures) line << "\n    " << f;
    for (const auto& f : r.starved)
      line << "\n    stop for a starved service (not a failure): " << f;
    std::cout << line.str() << std::endl;
  }
};

Chaos::Chaos(Options options) : impl_(std::make_unique<Impl>(std::move(options))) {}
Chaos::~Chaos() = default;

std::vector<std::string> Chaos::start() { return impl_->start(); }

RoundReport Chaos::round(const std::vector<Kill>& kills) { return impl_->round(kills); }

RoundReport Chaos::random_round(std::mt19937& rng) {
  std::vector<std::string> pool;
  for (const auto& s : impl_->started) pool.push_back(s);
  std::shuffle(pool.begin(), pool.end(), rng);
  std::uniform_int_distribution<int> first_ms(0, 3000), second_ms(0, 1500);
  std::bernoulli_distribution two(0.25);
  std::vector<Kill> kills = {{pool[0], std::chrono::milliseconds(first_ms(rng))}};
  if (two(rng))
    kills.push_back({pool[1], kills[0].after + std::chrono::milliseconds(second_ms(rng))});
  return round(kills);
}

TaskReport Chaos::stop() {
  impl_->task_stop = true;
  if (impl_->task.joinable()) impl_->task.join();
  {
    std::lock_guard lock(impl_->m);
    impl_->stopped_at = Clock::now();
  }
  TaskReport report = impl_->task_report();
  if (impl_->up) impl_->up->stop(30s);
  return report;
}

uint32_t Chaos::model_version() const {
  std::lock_guard lock(impl_->m);
  return impl_->model_version;
}

std::string Chaos::logs() const { return impl_->logs(); }

Options demo_options(const std::string& run_dir) {
  Options o;
  o.assembly = CONCERT_SOURCE_DIR "/deploy/demo/sanding_robot.yaml";
  o.swap_to = CONCERT_SOURCE_DIR "/deploy/demo/drill_robot.yaml";
  o.world = CONCERT_SOURCE_DIR "/deploy/demo/drill_site.yaml";
  o.run_dir = run_dir;
  return o;
}

std::string summary(const TaskReport& task, const std::vector<RoundReport>& rounds) {
  int resets_lost = 0;
  for (const auto& r : rounds) resets_lost += r.resets_lost;
  std::ostringstream out;
  out << "task: " << task.sent << " requests, " << task.succeeded << " succeeded, "
      << task.failed_safety_stop << " failed for a safety stop, " << task.failed_other
      << " failed otherwise, " << task.lost_with_planner << " lost with the killed planner, "
      << task.lost << " lost; operator resets sent again: " << resets_lost << "\n"
      << std::fixed << std::setprecision(2) << "requests taken by the planner later than "
      << std::chrono::duration<double>(kAckReported).count() << " s: " << task.acknowledged_late
      << " (slowest " << task.slowest_ack_s << " s; a figure, not a loss)\n";
  for (const auto& d : task.details) out << "  " << d << "\n";
  return out.str();
}

std::string figures(const std::vector<RoundReport>& rounds) {
  std::map<std::string, std::vector<double>> per;
  for (const auto& r : rounds)
    for (const auto& [s, t] : r.kill_to_ready_s) per[s].push_back(t);
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  for (auto& [s, v] : per) {
    std::sort(v.begin(), v.end());
    const double median =
        v.size() % 2 == 1 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    out << std::left << std::setw(10) << s << " n " << std::setw(3) << v.size() << " median "
        << median << " s  max " << v.back() << " s\n";
  }
  return out.str();
}

}  // namespace concert::system_test::chaos
