#include "launcher.hpp"
#include "sim_channel.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <optional>
#include <csignal>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <thread>

#include "concert/bim/model.hpp"
#include "concert/bim/storey_world.hpp"
#include "concert/common/clock.hpp"
#include "concert/dds/catalogue.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/idl_schema/cdr.hpp"
#include "concert/simbus/assembly.hpp"
#include "scan_verbs.hpp"
#include "concert/world/world.hpp"

namespace concert::tool {

namespace fs = std::filesystem;

std::chrono::milliseconds restart_delay(const BackoffParams& backoff,
                                        std::chrono::steady_clock::duration ran, int& failures) {
  failures = ran >= backoff.stable ? 1 : failures + 1;
  const auto delay = backoff.first * (int64_t{1} << std::min(failures - 1, 20));
  return std::min(delay, backoff.max);
}

Supervisor::Supervisor(std::vector<ServiceSpec> services, fs::path log_dir, std::ostream& log, BackoffParams backoff)
    : log_dir_(std::move(log_dir)), log_(log), backoff_(backoff) {
  for (auto& s : services) children_.push_back(Child{std::move(s)});
  fs::create_directories(log_dir_);
}

Supervisor::~Supervisor() { stop_all(); }

void Supervisor::say(const std::string& line) {
  const double t = std::chrono::duration<double>(Clock::now() - t0_).count();
  log_ << "[up " << std::fixed << std::setprecision(2) << std::setw(7) << t << " s] " << line << std::endl;
}

void Supervisor::start(Child& child) {
  const auto log_file = log_dir_ / (child.spec.name + ".log");
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    say("cannot fork for " + child.spec.name);
    child.restart_at = Clock::now() + backoff_.max;
    return;
  }
  if (pid == 0) {
    const int fd = open(log_file.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    const int in = open("/dev/null", O_RDONLY);
    dup2(fd, 1);
    dup2(fd, 2);
    dup2(in, 0);
    setpgid(0, 0);  // Ctrl-C in the terminal reaches `concert up`, which stops the services in order
    // A `concert up` that dies without stopping them (SIGKILL, a crash) takes its services along:
    // orphans kept a whole stack running on the domain (a test that ended at an assertion left
    // one, and the next test on the machine starved).
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);
    std::vector<char*> argv;
    for (auto& a : child.spec.argv) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  child.pid = pid;
  child.started = Clock::now();
  child.restart_at.reset();
  say("started " + child.spec.name + " (pid " + std::to_string(pid) + "), log " + log_file.string());
}

void Supervisor::start_all() {
  for (auto& c : children_) start(c);
}

void Supervisor::poll() {
  for (auto& c : children_) {
    if (c.pid > 0) {
      int status = 0;
      if (waitpid(c.pid, &status, WNOHANG) != c.pid) continue;
      const std::string how = WIFEXITED(status) ? "exited with code " + std::to_string(WEXITSTATUS(status))
                                                : "was killed by signal " + std::to_string(WTERMSIG(status));
      c.pid = -1;
      const auto delay = restart_delay(backoff_, Clock::now() - c.started, c.failures_in_a_row);
      c.restart_at = Clock::now() + delay;
      ++c.restarts;
      std::ostringstream msg;
      msg << c.spec.name << " " << how << "; restarting in " << std::fixed << std::setprecision(1)
          << std::chrono::duration<double>(delay).count() << " s (restart " << c.restarts << ", see "
          << (log_dir_ / (c.spec.name + ".log")).string() << ")";
      say(msg.str());
    } else if (c.restart_at && Clock::now() >= *c.restart_at) {
      start(c);
    }
  }
}

void Supervisor::stop_all(std::chrono::milliseconds grace) {
  bool any = false;
  for (auto it = children_.rbegin(); it != children_.rend(); ++it) {
    if (it->pid > 0) {
      kill(it->pid, SIGINT);
      any = true;
    }
    it->restart_at.reset();
  }
  if (!any) return;
  const auto deadline = Clock::now() + grace;
  for (auto& c : children_) {
    while (c.pid > 0) {
      int status = 0;
      if (waitpid(c.pid, &status, WNOHANG) == c.pid) {
        say("stopped " + c.spec.name);
        c.pid = -1;
      } else if (Clock::now() >= deadline) {
        kill(c.pid, SIGKILL);
        waitpid(c.pid, &status, 0);
        say("killed " + c.spec.name + " (did not stop within " + std::to_string(grace.count()) + " ms)");
        c.pid = -1;
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    }
  }
}

int Supervisor::restarts(const std::string& name) const {
  for (const auto& c : children_) {
    if (c.spec.name == name) return c.restarts;
  }
  return 0;
}

std::optional<pid_t> Supervisor::pid(const std::string& name) const {
  for (const auto& c : children_) {
    if (c.spec.name == name && c.pid > 0) return c.pid;
  }
  return std::nullopt;
}

std::string find_executable(const std::string& name, const std::string& service, const std::string& bin_dir) {
  auto executable = [](const fs::path& p) { return access(p.c_str(), X_OK) == 0 && fs::is_regular_file(p); };
  if (!bin_dir.empty() && executable(fs::path(bin_dir) / name)) return (fs::path(bin_dir) / name).string();
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path in_build = self.parent_path().parent_path().parent_path() / "services" / service / name;
    if (executable(in_build)) return in_build.string();
    if (executable(self.parent_path() / name)) return (self.parent_path() / name).string();
  }
  if (const char* path = std::getenv("PATH")) {
    std::istringstream dirs(path);
    for (std::string d; std::getline(dirs, d, ':');) {
      if (executable(fs::path(d) / name)) return (fs::path(d) / name).string();
    }
  }
  return "";
}

fs::path run_dir(int32_t domain) {
  const char* base = std::getenv("XDG_RUNTIME_DIR");
  return fs::path(base != nullptr && *base != '\0' ? base : "/tmp") / ("concert-d" + std::to_string(domain));
}

namespace {

using cli::Failure;
using cli::UsageError;

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

/// Copies `from` over `to` atomically (rename), so a watcher never sees a half-written file.
void install_file(const fs::path& from, const fs::path& to) {
  if (!fs::is_regular_file(from)) throw Failure(from.string() + ": no such file");
  const fs::path tmp = to.string() + ".tmp";
  fs::copy_file(from, tmp, fs::copy_options::overwrite_existing);
  fs::rename(tmp, to);
}

/// Rejects an assembly file that the robot could not mount: parse errors, unknown module keys,
/// connectors the parent does not have. The message names the file and what is wrong.
void check_assembly(const fs::path& file, const std::vector<std::string>& module_dbs) {
  if (!fs::is_regular_file(file)) throw Failure(file.string() + ": no such file");
  try {
    simbus::validate(simbus::load_assembly(file), load_catalogs(module_dbs));
  } catch (const std::exception& e) {
    throw Failure(std::string("assembly rejected, nothing changed: ") + e.what());
  }
}

void check_world(const fs::path& file) {
  if (!fs::is_regular_file(file)) throw Failure(file.string() + ": no such file");
  try {
    world::load_world_file(file.string());
  } catch (const std::exception& e) {
    throw Failure(std::string("world rejected, nothing changed: ") + e.what());
  }
}

int32_t domain_of(const std::optional<int32_t>& domain) {
  return domain ? *domain : cli::DdsOptions{}.domain_id();
}

}  // namespace

int run_up(const UpOptions& o, std::ostream& out, std::ostream& err) {
  const std::string& backend = o.backend;
  const std::string& assembly = o.assembly;
  const auto world = o.world.empty() ? std::nullopt : std::optional<std::string>(o.world);
  const auto& module_dbs = o.module_dbs;
  const std::string bin_dir = !o.bin_dir.empty()               ? o.bin_dir
                              : std::getenv("CONCERT_BIN_DIR") ? std::getenv("CONCERT_BIN_DIR")
                                                               : "";
  const double duration_s = o.duration_s;
  const int32_t domain = domain_of(o.domain);
  if (backend != "sim") {
    throw UsageError("--backend " + backend + ": only 'sim' runs on this machine (the EtherCAT backend needs the robot's master; see services/robot/README.md)");
  }
  // Validate inputs before anything starts: a bad file never disturbs a running stack.
  for (const auto& db : module_dbs) {
    if (!fs::is_directory(db)) throw Failure("--module-db " + db + ": no such folder");
  }
  check_assembly(assembly, module_dbs);
  if (world) check_world(*world);
  if (!o.ifc.empty() && o.storey.empty()) throw UsageError("--ifc needs --storey NAME");
  if (o.ifc.empty() && !o.storey.empty()) throw UsageError("--storey goes with --ifc");
  // The building's storey: the simulator's world (bim::storey_world) and nav's map, one file.
  // With --world too, that file is the simulated world (the storey as built, with what is drawn
  // on its walls: marks, plaster) and the IFC is nav's map.
  std::string ifc_world;
  if (!o.ifc.empty()) {
    out << "concert up: importing " << o.ifc << " (storey " << o.storey << ")" << std::endl;
    try {
      const bim::BimModel model = bim::load_ifc(o.ifc);
      const bim::Storey& storey = model.storey(o.storey);
      if (!world) {
        ifc_world = bim::world_yaml(bim::storey_world(model, storey));
        world::parse_world_yaml(ifc_world, o.ifc);
      }
    } catch (const std::exception& e) {
      throw Failure(std::string("--ifc: nothing started: ") + e.what());
    }
  }
  const std::vector<double> start = o.start.empty() ? std::vector<double>{0.0, 0.0, 0.0} : o.start;

  const fs::path dir = run_dir(domain);
  fs::create_directories(dir / "logs");
  // The simulator's assembly and world: the robot service writes accepted hot swaps and worlds
  // back over these copies (--keep-swaps), so that a robot service restarted after a crash
  // mounts what was mounted, in the world it was in. Without a world: an empty one.
  install_file(assembly, dir / "assembly.yaml");
  if (world) {
    install_file(*world, dir / "world.yaml");
  } else {
    std::ofstream(dir / "world.yaml", std::ios::trunc) << ifc_world;
  }
  // The simulated robot's start pose (robot.yaml's sim section; the rest stays the default).
  {
    std::ofstream params(dir / "robot_params.yaml");
    params << std::setprecision(17) << "sim:\n  base_position: [" << start[0] << ", " << start[1]
           << ", 0.0]\n  base_yaw: " << start[2] << "\n";
  }

  std::vector<std::string> db_args;
  for (const auto& db : module_dbs) {
    db_args.push_back("--module-db");
    db_args.push_back(fs::absolute(db).string());
  }
  struct Plan {
    std::string service, executable;
    std::vector<std::string> args;
    bool required;
  };
  std::vector<std::string> robot_args = {"--assembly", (dir / "assembly.yaml").string(),
                                         "--world",    (dir / "world.yaml").string(),
                                         "--params",   (dir / "robot_params.yaml").string(),
                                         "--keep-swaps"};
  robot_args.insert(robot_args.end(), db_args.begin(), db_args.end());
  // nav: the building's map when there is one, localised at the start pose.
  std::vector<std::string> nav_args;
  if (!o.ifc.empty()) {
    std::ostringstream x, y, yaw;
    x << std::setprecision(17) << start[0];
    y << std::setprecision(17) << start[1];
    yaw << std::setprecision(17) << start[2];
    nav_args = {"--ifc", fs::absolute(o.ifc).string(), "--storey", o.storey, "--initial-pose", x.str(), y.str(),
                yaw.str()};
  }
  // The operator GUI's gateway: its address, and the module databases whose meshes it serves.
  // Its port follows the domain by default, so stacks on other domains of one machine (tests,
  // other users) do not fight over one port.
  const int gui_port = o.gui_port >= 0 ? o.gui_port : 8080 + domain;
  std::vector<std::string> gui_args = {"--port", std::to_string(gui_port), "--bind", o.gui_bind};
  const bool gui_loopback = o.gui_bind == "localhost" || o.gui_bind == "::1" || o.gui_bind.rfind("127.", 0) == 0;
  if (!gui_loopback && o.gui_tls.empty()) {
    throw UsageError("--gui-bind " + o.gui_bind +
                     ": the GUI serves beyond this machine only over HTTPS: give --gui-tls DIR (a folder made by "
                     "`concert security init`)");
  }
  if (!o.gui_tls.empty()) gui_args.insert(gui_args.end(), {"--tls", fs::absolute(o.gui_tls).string()});
  if (!o.gui_users.empty()) gui_args.insert(gui_args.end(), {"--users", fs::absolute(o.gui_users).string()});
  if (o.gui_auth) gui_args.push_back("--auth");
  if (o.gui_pairing) gui_args.push_back("--pairing");
  gui_args.insert(gui_args.end(), db_args.begin(), db_args.end());
  // The planner's map: from the simulated world's description, the robot's own sensors, or both.
  std::vector<std::string> planner_args;
  if (!o.map.empty()) planner_args = {"--map", o.map};
  // The safety service keeps its latched state (a stop, its causes, the inputs, the services it
  // watches) in the run folder, so a safety service killed and restarted holds the same stop;
  // a new `concert up` starts from none.
  const fs::path safety_state = dir / "safety_state.yaml";
  fs::remove(safety_state);
  const std::vector<Plan> plan = {
      {"safety", "concert_safety", {"--state", safety_state.string()}, false},
      {"discovery", "concert_discovery", db_args, true},
      {"modelgen", "concert_modelgen", db_args, true},
      {"robot", "concert_robot", robot_args, true},
      {"planner", "concert_planner", planner_args, false},
      {"nav", "concert_nav", nav_args, false},
      {"drill", "concert_drill", {}, false},
      {"collab", "concert_collab", {}, false},
      {"surface_finish", "concert_surface_finish", {"--out-dir", (dir / "finish").string()}, false},
      {"gui", "concert_gui", gui_args, false},
  };
  std::vector<ServiceSpec> services;
  for (const auto& p : plan) {
    const std::string exe = find_executable(p.executable, p.service, bin_dir);
    if (exe.empty()) {
      if (p.required) throw Failure(p.executable + " not found (build it, or give --bin-dir / CONCERT_BIN_DIR)");
      err << "concert up: " << p.executable << " is not built; running without " << p.service << "\n";
      continue;
    }
    ServiceSpec spec{p.service, {exe}};
    spec.argv.insert(spec.argv.end(), p.args.begin(), p.args.end());
    services.push_back(std::move(spec));
  }
  // With the safety service up, the robot moves only while it hears it (a robot that cannot
  // hear the safety layer cannot hear its stops either): it holds until the first safety
  // state and whenever none came for 1 s (5 re-publications; the safety service's own
  // liveliness bound).
  if (std::any_of(services.begin(), services.end(), [](const ServiceSpec& s) { return s.name == "safety"; })) {
    for (auto& s : services) {
      if (s.name == "robot") s.argv.insert(s.argv.end(), {"--safety-timeout", "1.0"});
    }
  }

  setenv("CONCERT_DOMAIN_ID", std::to_string(domain).c_str(), 1);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  out << "concert up: domain " << domain << ", run folder " << dir.string() << "\n"
      << "  hot swap: concert sim swap FILE    status: concert status    stop: Ctrl-C" << std::endl;
  for (const auto& s : services) {
    if (s.name == "gui") {
      out << "  operator GUI: " << (o.gui_tls.empty() ? "http" : "https") << "://"
          << (o.gui_bind == "0.0.0.0" ? "<this host>" : o.gui_bind) << ":" << gui_port << "/"
          << (o.gui_pairing ? "  (pairing code: in " + (dir / "logs" / "gui.log").string() + ")" : "") << std::endl;
    }
  }
  Supervisor supervisor(std::move(services), dir / "logs", out);
  supervisor.start_all();
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                         std::chrono::duration<double>(duration_s));
  while (!g_stop && (duration_s == 0 || std::chrono::steady_clock::now() < until)) {
    supervisor.poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  out << "concert up: stopping" << std::endl;
  supervisor.stop_all();
  return 0;
}

struct SimChannel::Impl {
  dds::Participant participant;
  std::mutex m;
  std::condition_variable cv;
  std::optional<msg::SimCommandReply> reply;
  std::uint32_t awaited{0};
  dds::Reader<msg::SimCommandReply> replies;
  dds::Writer<msg::SimCommand> commands;
  std::uint32_t next_id;
  bool matched{false};

  explicit Impl(std::int32_t domain)
      : participant({.name = "concert_sim", .domain_id = domain}),
        replies(participant, dds::topics::sim_reply,
                [this](const msg::SimCommandReply& r, const auto&) {
                  {
                    std::lock_guard lock(m);
                    if (r.request_id() != awaited) return;
                    reply = r;
                  }
                  cv.notify_all();
                }),
        commands(participant, dds::topics::sim_command),
        next_id(static_cast<std::uint32_t>(std::chrono::steady_clock::now().time_since_epoch().count() & 0x7fffffff)) {}
};

SimChannel::SimChannel(std::int32_t domain) : impl_(std::make_unique<Impl>(domain)) {}
SimChannel::~SimChannel() = default;

std::int32_t SimChannel::domain() const { return impl_->participant.domain_id(); }

msg::SimCommandReply SimChannel::send(msg::SimCommandKind kind, const std::string& name, const std::string& content,
                                      std::chrono::milliseconds timeout) {
  Impl& i = *impl_;
  msg::SimCommand c;
  {
    std::lock_guard lock(i.m);
    i.awaited = i.next_id++;
    i.reply.reset();
    c.request_id(i.awaited);
  }
  c.stamp_ns(now_ns());
  c.source("concert sim");
  c.kind(kind);
  c.name(name);
  c.content(content);
  // The command topic is volatile: wait for the simulator's reader before writing.
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  if (!i.matched && !i.commands.wait_for_readers(1, timeout)) {
    throw Failure("no simulator on domain " + std::to_string(domain()) + " (start one with `concert up`)");
  }
  i.matched = true;
  // The reader matched may be another tool's (the GUI's gateway, a recorder) before the
  // simulator's: the command is written again every second until the reply comes (the
  // simulator answers a command it has seen again without applying it twice).
  std::unique_lock lock(i.m);
  while (!i.reply) {
    lock.unlock();
    i.commands.write(c);
    lock.lock();
    const auto next = std::min(deadline, std::chrono::steady_clock::now() + std::chrono::seconds(1));
    if (!i.cv.wait_until(lock, next, [&] { return i.reply.has_value(); }) &&
        std::chrono::steady_clock::now() >= deadline) {
      std::ostringstream s;
      s << "the simulator did not answer within " << std::chrono::duration<double>(timeout).count() << " s";
      throw Failure(s.str());
    }
  }
  return *i.reply;
}

int run_sim(const SimOptions& o, std::ostream& out, std::ostream& /*err*/) {
  if (o.verb != "assemble" && o.verb != "swap" && o.verb != "world") {
    throw UsageError("unknown sim verb '" + o.verb + "' (assemble, swap, world)");
  }
  const bool assembly = o.verb != "world";
  const bool from_ifc = !assembly && !o.ifc.empty();
  if (!assembly && o.file.empty() == o.ifc.empty()) {
    throw UsageError("sim world: give a world FILE or --ifc FILE --storey NAME (one of them)");
  }
  if (from_ifc && o.storey.empty()) throw UsageError("sim world --ifc: --storey NAME is required");
  std::stringstream content;
  std::string name = fs::path(o.file).filename().string();
  if (from_ifc) {
    // The storey's world (bim::storey_world), checked by the world parser like a file.
    try {
      const bim::BimModel model = bim::load_ifc(o.ifc);
      content << bim::world_yaml(bim::storey_world(model, model.storey(o.storey)));
      name = fs::path(o.ifc).filename().string() + " storey " + o.storey;
      world::parse_world_yaml(content.str(), name);
    } catch (const std::exception& e) {
      throw Failure(std::string("world rejected, nothing changed: ") + e.what());
    }
  } else {
    // Checked here first: a bad file never reaches the simulator (which checks again).
    if (assembly) {
      check_assembly(o.file, o.module_dbs);
    } else {
      check_world(o.file);
    }
    std::ifstream in(o.file);
    content << in.rdbuf();
  }

  SimChannel channel(o.dds.domain_id());
  const std::optional<msg::SimCommandReply> reply =
      channel.send(assembly ? msg::SIM_SWAP_ASSEMBLY : msg::SIM_SET_WORLD, name, content.str(), o.dds.timeout());
  if (!reply->accepted()) throw Failure(reply->message());
  if (o.dds.json) {
    out << idl::Json{{"verb", o.verb}, {"file", from_ifc ? o.ifc : o.file}, {"accepted", true},
                     {"message", reply->message()}}
               .dump()
        << "\n";
  } else {
    out << "concert sim " << o.verb << ": " << (from_ifc ? name : o.file) << ": "
        << reply->message() << "\n";
  }
  return 0;
}

void register_launcher_verbs(cli::Cli& concert) {
  auto up = std::make_shared<UpOptions>();
  CLI::App& up_verb =
      concert.verb(concert.app(), "up",
                   "start every service on this machine (simulated robot), restart one that dies, "
                   "stop all on Ctrl-C",
                   [&concert, up] { return run_up(*up, concert.out(), concert.err()); });
  up_verb.add_option("--assembly", up->assembly, "the mounted modules (an assembly file)")
      ->type_name("FILE")
      ->default_str(up->assembly);
  up_verb.add_option("--world", up->world, "the simulated world (walls, obstacles, marks, plaster); with --ifc, the building's storey as built (nav maps the IFC)")
      ->type_name("FILE");
  up_verb.add_option("--ifc", up->ifc, "a building: the simulated world and nav's map from one IFC storey")
      ->type_name("FILE");
  up_verb.add_option("--storey", up->storey, "with --ifc: the storey (name or GlobalId)")->type_name("NAME");
  up_verb.add_option("--start", up->start, "the robot's start pose in the world (nav starts localised there)")
      ->expected(3)
      ->type_name("X Y THETA")
      ->check(cli::real());
  up_verb
      .add_option("--module-db", up->module_dbs,
                  "module database folder (repeat to merge; default: the project's)")
      ->type_name("DIR");
  up_verb.add_option("--backend", up->backend, "robot backend (only sim runs on this machine)")
      ->type_name("sim|ethercat")
      ->default_str("sim");
  up_verb.add_flag_callback(
      "--sim", [up] { up->backend = "sim"; }, "the simulated robot (the default)");
  up_verb
      .add_option(
          "--bin-dir", up->bin_dir,
          "where the service executables are (default: CONCERT_BIN_DIR, the build tree, PATH)")
      ->type_name("DIR");
  up_verb.add_option("--duration", up->duration_s, "stop after S seconds (0: run until Ctrl-C)")
      ->type_name("S")
      ->check(cli::seconds());
  up_verb.add_option("--gui-port", up->gui_port, "the operator GUI's port (concert_gui)")
      ->type_name("N")
      ->check(cli::number(0, 65535, true))
      ->default_str("8080 + domain");
  up_verb.add_option("--gui-bind", up->gui_bind,
                     "the operator GUI's address (default: this machine only; 0.0.0.0: the robot's network, "
                     "with --gui-tls)")
      ->type_name("ADDR")
      ->default_str("127.0.0.1");
  up_verb.add_option("--gui-tls", up->gui_tls,
                     "the GUI serves HTTPS/WSS with the certificate of this PKI folder (concert security init)")
      ->type_name("DIR");
  up_verb.add_option("--gui-users", up->gui_users, "the GUI's users file (concert gui users)")->type_name("FILE");
  up_verb.add_flag("--gui-auth", up->gui_auth, "sign-in on a GUI bound to this machine too (always beyond it)");
  up_verb.add_flag("--gui-pairing", up->gui_pairing, "the GUI prints a one-time pairing code in its log");
  cli::Cli::add_choice(up_verb, "--map", up->map, {"world", "sensors", "both"},
                       "the planner's map: the simulated world's description, the robot's lidars and "
                       "depth cameras (paper 5.4.1), or both (default: the planner's, world)");
  cli::Cli::add_domain_option(up_verb, up->domain);

  CLI::App& sim =
      concert.group(concert.app(), "sim", "the running simulated robot: mounted modules, world, and the person holding it");
  for (const auto& [name, what] : std::vector<std::pair<std::string, std::string>>{
           {"assemble", "mount another assembly on the running simulated robot"},
           {"swap", "hot swap: mount another assembly on the running simulated robot"},
           {"world", "change the simulated world"}}) {
    auto o = std::make_shared<SimOptions>();
    o->verb = name;
    CLI::App& verb = concert.verb(
        sim, name, what, [&concert, o] { return run_sim(*o, concert.out(), concert.err()); });
    if (name == "world") {
      verb.add_option("FILE", o->file, "a world file (or --ifc)");
      verb.add_option("--ifc", o->ifc,
                      "build the world from a storey of this IFC file (bim::storey_world)")
          ->type_name("FILE");
      verb.add_option("--storey", o->storey, "with --ifc: the storey (name or GlobalId)")
          ->type_name("NAME");
    } else {
      verb.add_option("FILE", o->file, "an assembly file")->required();
    }
    if (name != "world") {
      verb.add_option("--module-db", o->module_dbs,
                      "module database folder to check the assembly against (repeat to merge)")
          ->type_name("DIR");
    }
    concert.add_dds_options(verb, o->dds, 10.0, "how long to wait for the simulator and its answer");
  }
  register_person_verbs(concert, sim);
}

}  // namespace concert::tool
