#pragma once
// Chaos under `concert up` (issue #21 "Trust"). The whole stack runs in simulation with a task
// running: drilling approaches planned by the planner and executed by the robot, one after the
// other between two areas of the demo wall, as `concert plan drill --execute` runs them.
// Services are killed with SIGKILL, one at a time or overlapping, and after each round the
// harness checks what must hold:
//  * every killed service is back, ready at the current model (version and content hash);
//  * a killed watched service (robot, planner, nav, drill) stops the robot with a safety stop
//    naming it; the stop stays until an operator reset, the robot holds through it (it does not
//    move, and a command sent meanwhile is refused naming the stop), and the task runs again
//    after the reset; killing any other service stops nothing. A killed robot service takes
//    the simulated robot with it (as a real robot's drives brake when their controller dies):
//    the restarted simulator mounts the modules that were mounted (`--keep-swaps`) at its
//    initial pose, and "holds" means it stays there, stopped, until the reset;
//  * the model, the module tree and the safety state are the same on the wire (for a reader
//    that joins after the round) and in the restarted service.
// It measures kill -> ready per service, commands (plan requests) lost and false stops.
// Shared by system_chaos_test (CI: every service in turn, then a short seeded random phase)
// and bench_chaos (a longer random phase whose figures go in the README).

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace concert::system_test::chaos {

using Clock = std::chrono::steady_clock;

/// The services `concert up` starts (when built), in its order.
const std::vector<std::string>& services();
/// Services whose silence the safety service turns into a stop (its default watch list).
bool watched(const std::string& service);

/// One kill of a round: `service` gets SIGKILL `after` the round's start.
struct Kill {
  std::string service;
  std::chrono::milliseconds after{0};
};

/// What one round saw; `failures` is empty when everything held. Each failure names the
/// service and the state that was wrong.
struct RoundReport {
  std::vector<Kill> kills;
  std::map<std::string, double> kill_to_ready_s;  ///< per killed service [s]
  bool stopped = false;                           ///< a safety stop happened in the round
  std::vector<std::string> causes;                ///< the stop's causes
  /// Stops naming a service nobody killed whose heartbeats this harness also heard go quiet
  /// (>= 0.5 s): the machine starved it; the stop was right (a false stop is a failure).
  std::vector<std::string> starved;
  double held_base_m = 0.0;     ///< largest base motion while stopped [m]
  double held_joint_rad = 0.0;  ///< largest joint motion while stopped [rad]
  std::string held_joint;       ///< the joint that moved most while stopped
  double hold_s = 0.0;          ///< how long the hold was watched [s]
  int resets_lost = 0;          ///< operator resets that got no answer (sent again)
  std::vector<std::string> failures;
};

/// The task's requests: each gets a final answer (succeeded, or failed with the reason) or is
/// lost. A request the planner was killed holding is lost with it (counted apart); any other
/// unanswered request is a lost command: never taken by the planner within a generous bound
/// (30 s, sent again every second meanwhile), or taken and never answered. How soon the planner
/// took them is a figure (taken later than 3 s: acknowledged_late), not a loss.
struct TaskReport {
  int sent = 0;
  int succeeded = 0;
  int failed_safety_stop = 0;        ///< refused or aborted by a safety stop (the reason says so)
  int failed_other = 0;              ///< failed for another reason (e.g. the robot was killed)
  int lost_with_planner = 0;         ///< the planner was killed while holding it
  int lost = 0;                      ///< no answer, planner alive: a lost command
  int acknowledged_late = 0;         ///< taken by the planner more than 3 s after sent
  double slowest_ack_s = 0.0;        ///< longest sent -> taken [s]
  std::vector<std::string> details;  ///< one line per request not succeeded
};

struct Options {
  std::string assembly;  ///< the robot `concert up` starts with
  std::string swap_to;   ///< "" or an assembly swapped in once up (model version 2)
  std::string world;     ///< the simulated world
  std::string run_dir;   ///< XDG_RUNTIME_DIR of the stack (its logs go there)
  /// Bounds. Generous: the machine is shared; they bound the waits, the figures are measured.
  std::chrono::seconds up_timeout{120};
  std::chrono::seconds ready_timeout{30};      ///< kill -> ready again
  std::chrono::seconds stop_timeout{5};        ///< after the last kill: the stop naming it
  std::chrono::seconds resume_timeout{90};     ///< after a reset: one request succeeded
  std::chrono::milliseconds hold_watch{1500};  ///< the stop is watched this long (no resume)
  bool print = true;                           ///< one line per round on stdout
};

class Chaos {
 public:
  explicit Chaos(Options options);
  ~Chaos();
  Chaos(const Chaos&) = delete;
  Chaos& operator=(const Chaos&) = delete;

  /// Starts the stack (and the swap), waits until every service is ready at one model and
  /// the safety state is RUNNING, then starts the task. Failures, empty when it came up.
  std::vector<std::string> start();
  /// Kills, waits for the services to come back, checks, resets a stop and waits for the task
  /// to run again.
  RoundReport round(const std::vector<Kill>& kills);
  /// A round of one or two random services at random moments (seeded by the caller's `rng`).
  RoundReport random_round(std::mt19937& rng);
  /// Stops the task and the stack; what the task's requests got.
  TaskReport stop();

  /// The current model (version, hash) as the harness knows it.
  uint32_t model_version() const;
  /// `concert up`'s output and the end of each service's log, for failure messages.
  std::string logs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The demo set-up: the sanding robot hot-swapped to the drill robot (so the current model is
/// version 2, not the one the robot started with) on the drill site; the stack's run folder
/// (XDG_RUNTIME_DIR) is `run_dir`.
Options demo_options(const std::string& run_dir);

/// What the task's requests got and the operator resets sent again over `rounds`, one line,
/// then one indented line per request not succeeded.
std::string summary(const TaskReport& task, const std::vector<RoundReport>& rounds);

/// Median and maximum of kill -> ready per service over `rounds`, one line per service
/// ("robot      n 3  median 1.23 s  max 1.50 s").
std::string figures(const std::vector<RoundReport>& rounds);

}  // namespace concert::system_test::chaos
