#pragma once
// Starts the stack's services as processes on this machine, restarts one that dies (with
// exponential back-off, logged) and stops all cleanly.

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"

namespace concert::tool {

struct ServiceSpec {
  std::string name;               ///< e.g. "discovery"
  std::vector<std::string> argv;  ///< argv[0] is the executable's path
};

/// Restart back-off: a service that dies is restarted after `first`, doubling while it keeps
/// dying within `stable` of its start (a crash loop), at most `max`; a run of `stable` or longer
/// resets it. `stable` is short: a service that was killed after it ran (chaos: kill -> ready
/// again aimed at <= 2 s) is restarted after `first`, not after a delay its earlier deaths
/// grew.
struct BackoffParams {
  std::chrono::milliseconds first{500};  ///< delay before the first restart
  std::chrono::milliseconds max{10'000};
  std::chrono::seconds stable{5};        ///< a run this long resets the back-off
};

/// The delay before restarting a service that died after running for `ran`; `failures` counts
/// its deaths in a row (runs shorter than `stable`) and is updated: first, 2 x first, 4 x first,
/// ... at most `max`, back to `first` after a run of `stable`.
std::chrono::milliseconds restart_delay(const BackoffParams& backoff,
                                        std::chrono::steady_clock::duration ran, int& failures);

class Supervisor {
 public:
  Supervisor(std::vector<ServiceSpec> services, std::filesystem::path log_dir, std::ostream& log,
             BackoffParams backoff = {});
  ~Supervisor();

  void start_all();
  /// Reaps services that exited and (re)starts those whose back-off has passed. Call often.
  void poll();
  /// SIGINT to every service, then SIGKILL after `grace`.
  void stop_all(std::chrono::milliseconds grace = std::chrono::milliseconds(5000));

  int restarts(const std::string& name) const;
  std::optional<pid_t> pid(const std::string& name) const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Child {
    ServiceSpec spec;
    pid_t pid = -1;
    int restarts = 0;
    int failures_in_a_row = 0;
    Clock::time_point started;
    std::optional<Clock::time_point> restart_at;
  };
  void start(Child& child);
  void say(const std::string& line);

  std::vector<Child> children_;
  std::filesystem::path log_dir_;
  std::ostream& log_;
  BackoffParams backoff_;
  Clock::time_point t0_ = Clock::now();
};

/// Where a service's executable is: `bin_dir`/NAME, else the build tree next to this program
/// (<build>/services/<service>/NAME), else PATH. Empty if not found.
std::string find_executable(const std::string& name, const std::string& service, const std::string& bin_dir);

/// Folder for one domain's running stack: assembly, world and logs
/// (${XDG_RUNTIME_DIR:-/tmp}/concert-d<domain>).
std::filesystem::path run_dir(int32_t domain);

/// `concert up`: what to start.
struct UpOptions {
  std::string backend = "sim";
  std::string assembly = CONCERT_DEFAULT_ASSEMBLY;
  std::string world;                    ///< "" = none
  std::string ifc;                      ///< a building: the world of its storey and nav's map ("" = none)
  std::string storey;                   ///< with ifc: the storey (name or GlobalId)
  std::vector<double> start;            ///< the robot's start pose x, y, yaw in the world (empty: 0 0 0)
  std::vector<std::string> module_dbs;  ///< "" = the project's
  std::string bin_dir;                  ///< "" = CONCERT_BIN_DIR, the build tree, PATH
  double duration_s = 0.0;              ///< 0 = until Ctrl-C
  std::optional<int32_t> domain;
  int gui_port = -1;                    ///< the operator GUI's port (services/gui); -1: 8080 + domain
  std::string gui_bind = "127.0.0.1";   ///< the operator GUI's address (localhost only by default)
  std::string gui_tls;                  ///< a PKI folder: the GUI serves HTTPS (needed beyond loopback)
  std::string gui_users;                ///< the GUI's users file ("" = its default)
  bool gui_auth = false;                ///< sign-in on a loopback GUI too
  bool gui_pairing = false;             ///< the GUI prints a one-time pairing code
  std::string map;                      ///< the planner's map: world, sensors or both ("" = its default)
};

/// `concert sim assemble|swap|world FILE`.
struct SimOptions {
  std::string verb;  ///< assemble, swap or world
  std::string file;  ///< assembly or world YAML on this host
  std::string ifc;     ///< world only: build the world from this IFC file's storey instead
  std::string storey;  ///< with ifc: the storey (name or GlobalId)
  std::vector<std::string> module_dbs;  ///< extra module databases to check the assembly against
  cli::DdsOptions dds;  ///< --domain, --timeout (for the simulator and its answer), --json
};

/// `concert sim person grip|walk|release|status`: the simulated person holding the robot.
struct PersonOptions {
  std::string verb;  ///< grip, walk, release, status
  std::string link;
  std::vector<double> guide;  ///< grip: DX DY DZ
  double guide_time{2.0};
  double stiffness{150.0}, damping{30.0}, speed{0.5}, wait_stretch{0.6}, let_go_stretch{1.0};
  std::vector<double> route;  ///< walk: DX DY pairs
  bool world_frame{false};    ///< walk: the route in world coordinates, not offsets from the hand
  bool wait{false};           ///< grip: until holding; walk: until arrived
  std::string until;          ///< status: wait for this phase
  cli::DdsOptions dds;
};
int run_sim_person(const PersonOptions& options, std::ostream& out, std::ostream& err);
/// Registers `concert sim person ...` under the `sim` group.
void register_person_verbs(cli::Cli& concert, CLI::App& sim);

int run_up(const UpOptions& options, std::ostream& out, std::ostream& err);
int run_sim(const SimOptions& options, std::ostream& out, std::ostream& err);

/// Registers `concert up` and `concert sim assemble|swap|world`.
void register_launcher_verbs(cli::Cli& concert);

}  // namespace concert::tool
