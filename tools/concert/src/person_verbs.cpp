// `concert sim person grip|walk|release|status`: the simulated person holding the robot
// (collaborative transport in simulation): orders over the simulator's command channel
// (SimCommand SIM_PERSON, world/person_order.hpp), and its state from status queries.

#include <chrono>
#include <iomanip>
#include <sstream>
#include <thread>

#include "concert/idl_schema/cdr.hpp"
#include "concert/world/person_order.hpp"
#include "launcher.hpp"
#include "sim_channel.hpp"

namespace concert::tool {

using cli::Failure;
using cli::UsageError;

namespace {

using Clock = std::chrono::steady_clock;

world::PersonReport status(SimChannel& channel, std::chrono::milliseconds timeout) {
  const msg::SimCommandReply r = channel.send(msg::SIM_PERSON, "concert sim person status", "action: status\n", timeout);
  if (!r.accepted()) throw Failure(r.message());
  try {
    return world::parse_person_report(r.message());
  } catch (const std::invalid_argument& e) {
    throw Failure(std::string("the simulator's person report is unreadable: ") + e.what());
  }
}

std::string describe(const world::PersonReport& p) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(2);
  s << "person " << world::to_string(p.phase);
  if (!p.link.empty()) s << " (" << p.link << ")";
  if (p.route_length > 0.0) s << ", walked " << p.walked << " of " << p.route_length << " m";
  s.precision(0);
  s << ", pull " << p.pull.norm() << " N (peak " << p.peak_pull << " N)";
  s.precision(2);
  s << ", the link " << (p.hand - p.tcp).head<2>().norm() << " m from the hand";
  if (!p.reason.empty()) s << ": " << p.reason;
  return s.str();
}

// Polls the person until it reaches `phase` (true) or lets go (false); throws Failure on timeout
// naming where it got to. Orders taken since `orders` only: an earlier report is stale.
bool wait_for(SimChannel& channel, world::PersonPhase phase, std::uint64_t orders, Clock::time_point deadline,
              std::chrono::milliseconds answer, world::PersonReport& last) {
  for (;;) {
    last = status(channel, answer);
    if (last.orders >= orders) {
      if (last.phase == phase) return true;
      if (last.phase == world::PersonPhase::kLetGo || last.phase == world::PersonPhase::kAbsent) return false;
    }
    if (Clock::now() >= deadline) throw Failure(std::string("not ") + world::to_string(phase) + " in time: " + describe(last));
    std::this_thread::sleep_for(std::chrono::milliseconds(250));  // a poll of the simulator, not a test wait
  }
}

}  // namespace

int run_sim_person(const PersonOptions& o, std::ostream& out, std::ostream& /*err*/) {
  world::PersonOrder order;
  std::optional<world::PersonPhase> until;
  if (o.verb == "grip") {
    order.action = world::PersonOrder::Action::kGrip;
    order.link = o.link;
    if (!o.guide.empty()) order.guide = Eigen::Vector3d(o.guide[0], o.guide[1], o.guide[2]);
    order.guide_time = o.guide.empty() ? 0.0 : o.guide_time;
    order.params.stiffness = o.stiffness;
    order.params.damping = o.damping;
    order.params.speed = o.speed;
    order.params.wait_stretch = o.wait_stretch;
    order.params.let_go_stretch = o.let_go_stretch;
    if (o.wait) until = world::PersonPhase::kHolding;
  } else if (o.verb == "walk") {
    if (o.route.empty() || o.route.size() % 2 != 0)
      throw UsageError("sim person walk: give the route as DX DY pairs (got " + std::to_string(o.route.size()) +
                       " numbers)");
    order.action = world::PersonOrder::Action::kWalk;
    for (std::size_t i = 0; i + 1 < o.route.size(); i += 2) order.route.emplace_back(o.route[i], o.route[i + 1]);
    order.relative = !o.world_frame;
    if (o.wait) until = world::PersonPhase::kArrived;
  } else if (o.verb == "release") {
    order.action = world::PersonOrder::Action::kRelease;
  } else if (o.verb == "status") {
    if (!o.until.empty()) {
      try {
        until = world::person_phase(o.until);
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("sim person status --until: ") + e.what());
      }
    }
  } else {
    throw UsageError("unknown sim person verb '" + o.verb + "' (grip, walk, release, status)");
  }
  const std::string content = o.verb == "status" ? std::string("action: status\n") : world::person_order_yaml(order);
  try {
    (void)world::parse_person_order(content, "concert sim person " + o.verb);  // the simulator checks again
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }

  const auto deadline = Clock::now() + o.dds.timeout();
  const auto answer = std::min<std::chrono::milliseconds>(o.dds.timeout(), std::chrono::seconds(10));
  SimChannel channel(o.dds.domain_id());
  std::string message;
  std::uint64_t orders = 0;
  if (o.verb != "status") {
    const world::PersonReport before = status(channel, answer);
    const msg::SimCommandReply r = channel.send(msg::SIM_PERSON, "concert sim person " + o.verb, content, answer);
    if (!r.accepted()) throw Failure(r.message());
    message = r.message();
    orders = before.orders + 1;
  }
  world::PersonReport last;
  bool reached = true;
  if (until) {
    reached = wait_for(channel, *until, orders, deadline, answer, last);
  } else {
    last = status(channel, answer);
  }
  if (o.dds.json) {
    const idl::Json person = {{"phase", world::to_string(last.phase)},
              {"link", last.link},
              {"reason", last.reason},
              {"walked", last.walked},
              {"route_length", last.route_length},
              {"pull", last.pull.norm()},
              {"peak_pull", last.peak_pull},
              {"hand", {last.hand.x(), last.hand.y(), last.hand.z()}},
              {"tcp", {last.tcp.x(), last.tcp.y(), last.tcp.z()}},
              {"time", last.time}};
    out << idl::Json{{"verb", "person " + o.verb}, {"accepted", true}, {"message", message}, {"reached", reached},
                     {"person", person}}
               .dump()
        << "\n";
  } else {
    out << "concert sim person " << o.verb << ": " << (message.empty() ? "" : message + "; ") << describe(last)
        << "\n";
  }
  if (!reached) throw Failure("the person let go: " + (last.reason.empty() ? describe(last) : last.reason));
  return 0;
}

void register_person_verbs(cli::Cli& concert, CLI::App& sim) {
  CLI::App& person = concert.group(sim, "person",
                                   "the simulated person holding the robot's gripper (collaborative transport in "
                                   "simulation)");
  const auto add = [&](const std::string& name, const std::string& what, double timeout) {
    auto o = std::make_shared<PersonOptions>();
    o->verb = name;
    CLI::App& verb =
        concert.verb(person, name, what, [&concert, o] { return run_sim_person(*o, concert.out(), concert.err()); });
    concert.add_dds_options(verb, o->dds, timeout, "how long to wait for the simulator (and with --wait or --until, the person)");
    return std::make_pair(&verb, o);
  };
  {
    auto [verb, o] = add("grip", "the person grips the link (the gripper's TCP) and holds it, or guides it first", 10.0);
    verb->add_option("--link", o->link, "the body held (default: the mounted robot's one gripper TCP)")->type_name("LINK");
    verb->add_option("--guide", o->guide, "the hand moves the link by this much (world frame) ...")
        ->expected(3)
        ->type_name("DX DY DZ")
        ->check(cli::real());
    verb->add_option("--guide-time", o->guide_time, "... over this long (simulated time)")
        ->type_name("S")
        ->check(cli::positive_seconds())
        ->capture_default_str();
    verb->add_option("--stiffness", o->stiffness, "the person's arm: spring [N/m]")->check(cli::number(0, 1e6, false, true))->capture_default_str();
    verb->add_option("--damping", o->damping, "and damper [N s/m]")->check(cli::number(0))->capture_default_str();
    verb->add_option("--speed", o->speed, "walking speed [m/s]")->check(cli::number(0, 5, false, true))->capture_default_str();
    verb->add_option("--wait-stretch", o->wait_stretch, "the link this far behind the hand: the person waits [m]")
        ->check(cli::number(0, 10, false, true))
        ->capture_default_str();
    verb->add_option("--let-go-stretch", o->let_go_stretch, "this far: the person lets go [m]")
        ->check(cli::number(0, 10, false, true))
        ->capture_default_str();
    verb->add_flag("--wait", o->wait, "return when the guiding is over and the person holds the link");
  }
  {
    auto [verb, o] = add("walk", "the person walks a route holding the link (follow-me)", 10.0);
    verb->add_option("ROUTE", o->route, "DX DY [DX DY ...]: the route's points from where the hand is [m]")
        ->required()
        ->type_name("DX DY")
        ->check(cli::real());
    verb->add_flag("--world", o->world_frame, "the route's points are the world's x, y, not offsets");
    verb->add_flag("--wait", o->wait, "return when the person arrived (exit 1 if it let go)");
  }
  add("release", "the person lets go", 10.0);
  {
    auto [verb, o] = add("status", "the person's phase, pull and place along its route", 10.0);
    verb->add_option("--until", o->until, "wait for this phase (guiding, holding, walking, waiting, arrived, let go, absent)")
        ->type_name("PHASE");
  }
}

}  // namespace concert::tool
