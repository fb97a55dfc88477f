#include "drill/mission_tree.hpp"

#include <algorithm>
#include <numeric>

#include "bt/bt.hpp"
#include "concert/common/text.hpp"

namespace concert::drill {
namespace {

constexpr double kSameHole = 0.01;  // [m] a hole of a previous run within this is the same hole

// What the running action waits for: the time until the next tick is counted there.
enum class Work { kNone, kNavigate, kPlan, kExecute, kDrill };
// Which part of an area's or a hole's time it is (AreaTimes, HoleTimes).
enum class Step { kNone, kApproach, kDetect, kSurvey, kPlace, kAlign, kDrill, kRetract };

bool was_drilled(const HoleReport& hole) {
  return hole.state == HoleState::kDrilled ||
         (hole.state == HoleState::kSkipped && hole.reason == kDrilledBefore);
}

bool failed(const HoleReport& hole) { return hole.state == HoleState::kFailed; }

std::string quoted(const std::string& kind, const std::string& name) {
  return kind + " '" + name + "'";
}

}  // namespace

const char* to_string(HoleState s) {
  switch (s) {
    case HoleState::kPending:
      return "pending";
    case HoleState::kDrilled:
      return "drilled";
    case HoleState::kFailed:
      return "failed";
    case HoleState::kSkipped:
      return "skipped";
  }
  return "?";
}

const char* to_string(AreaState s) {
  switch (s) {
    case AreaState::kPending:
      return "pending";
    case AreaState::kActive:
      return "active";
    case AreaState::kDone:
      return "done";
    case AreaState::kFailed:
      return "failed";
    case AreaState::kSkipped:
      return "skipped";
  }
  return "?";
}

const char* to_string(MissionState s) {
  switch (s) {
    case MissionState::kIdle:
      return "idle";
    case MissionState::kRunning:
      return "running";
    case MissionState::kSucceeded:
      return "succeeded";
    case MissionState::kFailed:
      return "failed";
    case MissionState::kAborted:
      return "aborted";
  }
  return "?";
}

int MissionReport::holes_drilled() const {
  int n = 0;
  for (const auto& area : areas) {
    n += static_cast<int>(std::count_if(area.holes.begin(), area.holes.end(), [](const auto& h) {
      return h.state == HoleState::kDrilled;
    }));
  }
  return n;
}

int MissionReport::holes_marked() const {
  int n = 0;
  for (const auto& area : areas) n += static_cast<int>(area.holes.size());
  return n;
}

// The tree of Fig. 11 over the ports, and the report it fills. The tree's nodes call back into
// this object; `current_area` and `current_hole` are the loops' current items.
struct MissionTree::Impl {
  Impl(Mission m, MissionPorts& p) : mission(std::move(m)), ports(p) {
    report.mission = mission.name;
    for (const auto& spec : mission.areas) report.areas.push_back({.name = spec.name});
    drilled_before.resize(mission.areas.size());
    plan_started.resize(mission.areas.size(), false);
    asked_again.resize(mission.areas.size(), false);
    root = build();
  }

  Mission mission;
  MissionPorts& ports;
  MissionReport report;
  std::unique_ptr<bt::Node> root;
  std::vector<std::vector<Eigen::Vector3d>> drilled_before;  // per area: hole origins [m]
  std::vector<bool> plan_started;                            // per area
  std::vector<bool> asked_again;  // per area: its unreachable holes were surveyed a second time
  std::vector<std::pair<std::size_t, HoleReport>> reopened;  // those holes as the first survey left them
  std::vector<DrillPoint> detected;
  std::vector<std::size_t> surveying;   // the area's holes surveyed (report indices)
  std::vector<std::size_t> placing;     // the area's holes placed for (report indices)
  std::vector<std::size_t> hole_order;  // the order to drill them, as the placement said
  std::size_t current_area{0};
  std::size_t current_hole{0};
  bool hole_active{false};
  bool started{false};
  double last_now{0.0};
  Work waiting{Work::kNone};
  Step waiting_step{Step::kNone};
  std::size_t step_area{0}, step_hole{0};  // whose step it is
  std::string fatal;  // why the mission cannot go on safely (set by a failed retraction)
  std::string stow_failure;  // why the arm did not go home at the end
  bool moved{false};         // a motion was started (navigate, execute, place, align)

  AreaReport& area() { return report.areas[current_area]; }
  HoleReport& hole() { return area().holes[current_hole]; }
  bool finished() const {
    return report.state != MissionState::kIdle && report.state != MissionState::kRunning;
  }

  // --- the tree ---------------------------------------------------------------------------

  // An action whose waiting time counts as `work`, and as `step` of the current area or hole.
  bt::NodePtr action(std::string name, Work work, std::function<void()> start,
                     std::function<Outcome()> poll, Step step = Step::kNone) {
    return std::make_unique<bt::Action>(std::move(name), std::move(start),
                                        [this, work, step, poll = std::move(poll)] {
                                          Outcome outcome = poll();
                                          if (outcome.progress == Progress::kRunning) {
                                            waiting = work;
                                            waiting_step = step;
                                            step_area = current_area;
                                            step_hole = current_hole;
                                          }
                                          return outcome;
                                        });
  }

  // The areas still to work on (not done before, located), in mission order.
  std::vector<std::size_t> pending_areas() const {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < report.areas.size(); ++i) {
      if (report.areas[i].state == AreaState::kPending) out.push_back(i);
    }
    return out;
  }

  // A loop over pending_areas(); with `activate`, the area worked on is kActive.
  bt::NodePtr for_each_area(std::string name, bool activate,
                            std::function<bool(std::size_t, bt::Status, const std::string&)> end,
                            bt::NodePtr body) {
    bt::ForEach::Hooks hooks{
        .items = [this] { return pending_areas(); },
        .label = [this](std::size_t i) { return quoted("area", report.areas[i].name); },
        .begin =
            [this, activate](std::size_t i) {
              current_area = i;
              current_hole = 0;
              if (activate) area().state = AreaState::kActive;
            },
        .end = std::move(end)};
    return std::make_unique<bt::ForEach>(std::move(name), std::move(hooks), std::move(body));
  }

  bt::NodePtr build() {
    using bt::hidden;
    using bt::sequence;
    auto resolve = action(
        "resolve", Work::kNone,
        [this] { ports.resolve(current_area, mission.areas[current_area]); },
        [this] { return ports.resolution(current_area, area().located); });
    auto initialise =
        sequence("initialise", for_each_area(
                                   "areas", false,
                                   [this](std::size_t, bt::Status status, const std::string& why) {
                                     return area_resolved(status, why);
                                   },
                                   std::move(resolve)));

    auto navigate = bt::fallback(
        "navigate if the area has a base pose",
        std::make_unique<bt::Condition>("no base pose", [this] { return !area().located.base; }),
        action(
            "navigate", Work::kNavigate,
            [this] {
              moved = true;
              ports.navigate(*area().located.base);
            },
            [this] { return ports.navigation(); }, Step::kApproach));
    // Waits for the area's plan; starts it from the robot's current state if it was not planned
    // ahead: the first area, an area the base navigated to, an area after one whose approach
    // failed.
    auto plan = action(
        "plan", Work::kPlan,
        [this] {
          if (!plan_started[current_area]) start_plan(current_area, std::nullopt);
        },
        [this] { return ports.planning(current_area); }, Step::kApproach);
    auto execute = action(
        "execute", Work::kExecute,
        [this] {
          moved = true;
          ports.execute(current_area);
        },
        [this] { return executed(); }, Step::kApproach);
    auto plan_next = action(
        "plan the next area", Work::kNone, [this] { plan_next_area(); },
        [] { return Outcome::succeeded(); });
    auto detect = action(
        "detect", Work::kDrill,
        [this] { ports.detect(current_area, mission.areas[current_area], area().located); },
        [this] { return detection(); }, Step::kDetect);

    // Which holes the robot can reach at all, before anything moves for them (the others are
    // reported with the planner's reason and not attempted), one base placement for the
    // reachable ones (drill/placement.hpp), and each of those aligned, drilled and retracted.
    const auto survey_and_drill = [&](const std::string& pass) {
      auto survey = action(
          "survey" + pass, Work::kPlan,
          [this] {
            surveying = pending_holes();
            ports.classify(current_area, pending_points());
          },
          [this] { return surveyed(); }, Step::kSurvey);
      auto place = action(
          "place", Work::kDrill,
          [this] {
            moved = true;
            placing = pending_holes();
            hole_order.clear();
            ports.place(current_area, pending_points());
          },
          [this] { return placed(); }, Step::kPlace);
      auto align = action(
          "align", Work::kDrill,
          [this] {
            moved = true;
            ports.align(hole().point);
          },
          [this] { return ports.alignment(); }, Step::kAlign);
      auto drill = action(
          "drill", Work::kDrill, [this] { ports.drill(hole().point, mission.depth); },
          [this] { return ports.drilling(); }, Step::kDrill);
      auto retract = action(
          "retract", Work::kDrill, [this] { ports.retract(); }, [this] { return retraction(); },
          Step::kRetract);
      auto hole_body = std::make_unique<bt::Finally>(
          "hole", hidden(sequence("align and drill", std::move(align), std::move(drill))),
          std::move(retract));
      bt::ForEach::Hooks hole_hooks{
          .items = [this] { return ordered_holes(); },
          .label = [this](std::size_t i) { return quoted("hole", area().holes[i].point.label); },
          .begin =
              [this](std::size_t i) {
                current_hole = i;
                hole_active = true;
              },
          .end = [this](std::size_t, bt::Status status,
                        const std::string& why) { return hole_done(status, why); }};
      auto holes =
          std::make_unique<bt::ForEach>("holes", std::move(hole_hooks), hidden(std::move(hole_body)));
      auto drill_reachable = bt::fallback(
          "drill the reachable holes", std::make_unique<bt::Condition>("no hole reachable", [this] { return pending_holes().empty(); }),
          hidden(sequence("place and drill", std::move(place), std::move(holes))));
      return hidden(sequence("survey and drill" + pass, std::move(survey), hidden(std::move(drill_reachable))));
    };
    // The holes the first survey judged unreachable, asked once more after the area's other
    // holes were drilled: the robot then stands elsewhere, and the planner's map of what is
    // around it is new (what the sensors saw at the first survey may have been in the way only
    // then).
    auto again = bt::fallback(
        "survey again",
        std::make_unique<bt::Condition>("nothing to ask again", [this] { return !reopen_unreachable(); }),
        survey_and_drill(" again"));

    auto area_body =
        sequence("area", hidden(std::move(navigate)), std::move(plan), std::move(execute),
                 std::move(plan_next), std::move(detect), survey_and_drill(""), hidden(std::move(again)));
    auto areas = for_each_area(
        "areas", true,
        [this](std::size_t, bt::Status status, const std::string& why) {
          return area_done(status, why);
        },
        hidden(std::move(area_body)));
    // The arm home from wherever the last area left it: the robot ends ready to drive or to
    // have its tool swapped. Not after a fatal retraction (the bit may be in the wall), an
    // abort or a failed health check: those end the mission before this node.
    // Nothing moved (every area done before, or none located): nothing to stow.
    auto stow_action = action(
        "stow the arm", Work::kExecute, [this] { ports.stow(); },
        [this] {
          Outcome outcome = ports.stowing();
          if (outcome.progress == Progress::kFailed) {
            stow_failure = outcome.reason;
            return Outcome::succeeded();  // the holes' outcome stands; conclude() adds this
          }
          return outcome;
        });
    auto stow = bt::fallback("stow the arm if anything moved",
                             std::make_unique<bt::Condition>("nothing moved", [this] { return !moved; }),
                             std::move(stow_action));
    return sequence("mission", std::move(initialise), std::move(areas), hidden(std::move(stow)));
  }

  // --- what the nodes do --------------------------------------------------------------------

  bool area_resolved(bt::Status status, const std::string& why) {
    if (status == bt::Status::kFailure) {
      area().state = AreaState::kFailed;
      area().reason = why;
    }
    return true;
  }

  void start_plan(std::size_t i, std::optional<std::size_t> after) {
    ports.plan(i, report.areas[i].located.frame, after);
    plan_started[i] = true;
  }

  // Plans the next area while this one is detected and drilled: from this area's approach
  // posture, where the arm is back after every hole. Not if the next area has a base pose: the
  // base moves first, and that area is planned from where it stops.
  void plan_next_area() {
    const std::vector<std::size_t> pending = pending_areas();
    const auto next = std::find_if(pending.begin(), pending.end(),
                                   [this](std::size_t i) { return i > current_area; });
    if (next != pending.end() && !report.areas[*next].located.base) start_plan(*next, current_area);
  }

  // A failed approach leaves the arm somewhere along its trajectory: stop() holds it there and
  // the mission goes on with the next area. Safe as far as the mission can tell: the next area is
  // planned from the robot's measured state (no plan was started from this area's posture: that
  // happens only after a successful approach), the planner refuses a start state in collision
  // (which fails that area in turn, without moving), and e-stops, limits and lost services end
  // the mission through health() on every tick. Not safe if the trajectory failed because the
  // arm touched something that none of these reports: the next approach then moves an arm in
  // contact. The reason is in the report for the operator to judge.
  Outcome executed() {
    Outcome outcome = ports.execution();
    if (outcome.progress == Progress::kFailed) ports.stop();
    return outcome;
  }

  Outcome detection() {
    detected.clear();
    Outcome outcome = ports.detection(detected);
    if (outcome.progress != Progress::kSucceeded) return outcome;
    if (detected.empty()) return Outcome::failed("no drilling point found");
    select_holes();
    return outcome;
  }

  // The detected points as holes: the nearest to the centre when more were found than the area
  // expects, and not those a previous run drilled.
  void select_holes() {
    AreaReport& a = area();
    a.holes.clear();
    for (auto& point : detected) a.holes.push_back({.point = std::move(point)});
    const auto expected = static_cast<std::size_t>(mission.areas[current_area].expected);
    if (expected > 0 && a.holes.size() > expected) {
      const Eigen::Vector3d centre = a.located.frame.translation();
      auto distance = [&](std::size_t i) {
        return (a.holes[i].point.frame.translation() - centre).norm();
      };
      std::vector<std::size_t> order(a.holes.size());
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t x, std::size_t y) { return distance(x) < distance(y); });
      for (std::size_t k = expected; k < order.size(); ++k) {
        a.holes[order[k]].state = HoleState::kSkipped;
        a.holes[order[k]].reason = "the area expects " + std::to_string(expected) + " holes and " +
                                   std::to_string(a.holes.size()) +
                                   " were found: nearer ones to its centre are drilled";
      }
    }
    for (auto& h : a.holes) {
      const bool before =
          std::any_of(drilled_before[current_area].begin(), drilled_before[current_area].end(),
                      [&](const Eigen::Vector3d& p) {
                        return (p - h.point.frame.translation()).norm() <= kSameHole;
                      });
      if (h.state == HoleState::kPending && before) {
        h.state = HoleState::kSkipped;
        h.reason = kDrilledBefore;
      }
    }
  }

  // The survey's verdicts onto the holes: an unreachable one is skipped with the planner's
  // reason. Verdicts that do not name each hole surveyed once leave every hole as it was. A
  // survey that failed (nothing moved) leaves them unjudged: the holes are attempted.
  Outcome surveyed() {
    std::vector<HoleReach> reach;
    const Outcome outcome = ports.classification(reach);
    if (outcome.progress == Progress::kRunning) return outcome;
    if (outcome.progress == Progress::kSucceeded && reach.size() == surveying.size()) {
      auto& holes = area().holes;
      for (std::size_t k = 0; k < reach.size(); ++k) {
        HoleReport& h = holes[surveying[k]];
        h.reach = reach[k];
        if (reach[k].reach == Reach::kUnreachable) {
          h.state = HoleState::kSkipped;
          h.reason = "unreachable: " + reach[k].why;
        }
      }
    } else {
      // A second survey that gave no verdicts leaves its holes as the first one judged them
      // (not attempted blind).
      for (const auto& [i, before] : reopened) area().holes[i] = before;
    }
    reopened.clear();
    return Outcome::succeeded();
  }

  // The area's holes the survey skipped as unreachable back to pending, once per area and only
  // when one of its holes was drilled since (the robot moved); true if there were any.
  bool reopen_unreachable() {
    if (!fatal.empty() || asked_again[current_area]) return false;
    auto& holes = area().holes;
    const bool drilled = std::any_of(holes.begin(), holes.end(),
                                     [](const HoleReport& h) { return h.state == HoleState::kDrilled; });
    if (!drilled) return false;
    bool any = false;
    reopened.clear();
    for (std::size_t i = 0; i < holes.size(); ++i) {
      HoleReport& h = holes[i];
      if (h.state == HoleState::kSkipped && h.reach.reach == Reach::kUnreachable) {
        reopened.emplace_back(i, h);
        h.state = HoleState::kPending;
        h.reason.clear();
        h.reach = HoleReach{};
        any = true;
      }
    }
    asked_again[current_area] = any;
    return any;
  }

  // A placement that failed left the whole body somewhere along its move: held there, and the
  // area fails (as an approach does, executed()). One that succeeded says the holes' order:
  // kept when it names each hole placed for once (else the order they came in).
  Outcome placed() {
    std::vector<std::size_t> order;
    Outcome outcome = ports.placement(order);
    if (outcome.progress == Progress::kFailed) ports.stop();
    if (outcome.progress != Progress::kSucceeded) return outcome;
    std::vector<std::size_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::size_t> all(placing.size());
    std::iota(all.begin(), all.end(), 0);
    if (sorted == all) {
      for (const std::size_t i : order) hole_order.push_back(placing[i]);
    }
    return outcome;
  }

  // The pending holes in the placement's order, then any other pending hole in report order.
  std::vector<std::size_t> ordered_holes() const {
    const std::vector<std::size_t> pending = pending_holes();
    std::vector<std::size_t> out;
    for (const std::size_t i : hole_order) {
      if (std::find(pending.begin(), pending.end(), i) != pending.end()) out.push_back(i);
    }
    for (const std::size_t i : pending) {
      if (std::find(out.begin(), out.end(), i) == out.end()) out.push_back(i);
    }
    return out;
  }

  std::vector<DrillPoint> pending_points() const {
    std::vector<DrillPoint> out;
    for (const std::size_t i : pending_holes()) out.push_back(report.areas[current_area].holes[i].point);
    return out;
  }

  std::vector<std::size_t> pending_holes() const {
    std::vector<std::size_t> out;
    const auto& holes = report.areas[current_area].holes;
    for (std::size_t i = 0; i < holes.size(); ++i) {
      if (holes[i].state == HoleState::kPending) out.push_back(i);
    }
    return out;
  }

  // A retraction that failed leaves the bit where it is, maybe in the wall, and the arm away from
  // the approach posture the next hole and the next area's plan start from: nothing may move
  // until someone looked, so the mission stops.
  Outcome retraction() {
    Outcome outcome = ports.retraction();
    if (outcome.progress == Progress::kFailed) {
      fatal = quoted("area", area().name) + " " + quoted("hole", hole().point.label) +
              ": retract: " + outcome.reason +
              "; the arm is not back at the approach posture (the bit may be in the wall): "
              "mission stopped";
    }
    return outcome;
  }

  bool hole_done(bt::Status status, const std::string& why) {
    hole_active = false;
    if (status == bt::Status::kSuccess) {
      hole().state = HoleState::kDrilled;
    } else {
      hole().state = HoleState::kFailed;
      hole().reason = why;
    }
    return fatal.empty();
  }

  bool area_done(bt::Status status, const std::string& why) {
    AreaReport& a = area();
    if (status == bt::Status::kFailure) {
      a.state = AreaState::kFailed;
      a.reason = why;
      return fatal.empty();
    }
    std::vector<std::string> problems;
    const auto n_failed = std::count_if(a.holes.begin(), a.holes.end(), failed);
    if (n_failed > 0) {
      const auto first = std::find_if(a.holes.begin(), a.holes.end(), failed);
      problems.push_back(std::to_string(n_failed) + " of " + std::to_string(a.holes.size()) +
                         " holes failed (" + quoted("hole", first->point.label) + ": " +
                         first->reason + ")");
    }
    const auto unreachable = [](const HoleReport& h) {
      return h.state == HoleState::kSkipped && h.reach.reach == Reach::kUnreachable;
    };
    const auto n_unreachable = std::count_if(a.holes.begin(), a.holes.end(), unreachable);
    if (n_unreachable > 0) {
      const auto first = std::find_if(a.holes.begin(), a.holes.end(), unreachable);
      problems.push_back(std::to_string(n_unreachable) + " of " + std::to_string(a.holes.size()) +
                         " holes unreachable (" + quoted("hole", first->point.label) + ": " +
                         first->reach.why + ")");
    }
    const int expected = mission.areas[current_area].expected;
    const int found = static_cast<int>(a.holes.size());
    if (found < expected) {
      problems.push_back(std::to_string(expected - found) + " of " + std::to_string(expected) +
                         " expected holes not found");
    }
    a.state = problems.empty() ? AreaState::kDone : AreaState::kFailed;
    a.reason = join(problems, "; ");
    return true;
  }

  // --- the mission's end --------------------------------------------------------------------

  void finish(MissionState state, std::string reason) {
    report.state = state;
    report.reason = std::move(reason);
  }

  // Stops the robot and ends the mission; the area and hole it was working on fail with `why`.
  void halt(MissionState state, const std::string& why) {
    ports.stop();
    if (current_area < report.areas.size() && area().state == AreaState::kActive) {
      area().state = AreaState::kFailed;
      area().reason = "stopped: " + why;
      if (hole_active) {
        hole().state = HoleState::kFailed;
        hole().reason = "stopped: " + why;
      }
    }
    finish(state, why);
  }

  // Every area done and no hole failed: succeeded; else failed, with what went wrong.
  void conclude() {
    std::vector<std::string> problems;
    std::ptrdiff_t n_failed = 0;
    for (const auto& a : report.areas)
      n_failed += std::count_if(a.holes.begin(), a.holes.end(), failed);
    if (n_failed > 0) {
      problems.push_back(std::to_string(n_failed) + " of " + std::to_string(report.holes_marked()) +
                         " holes failed");
    }
    for (const auto& a : report.areas) {
      if (a.state != AreaState::kDone && a.state != AreaState::kSkipped) {
        problems.push_back(quoted("area", a.name) + ": " + a.reason);
      }
    }
    if (!stow_failure.empty()) {
      problems.push_back("the arm did not go home at the end (" + stow_failure +
                         "): move it clear, then `concert plan home`");
    }
    if (problems.empty()) {
      finish(MissionState::kSucceeded, "");
    } else {
      finish(MissionState::kFailed, join(problems, "; "));
    }
  }

  // Adds the time since the last tick to what the mission waited for.
  void account(double now) {
    if (!started) {
      started = true;
      last_now = now;
      return;
    }
    const double dt = std::max(0.0, now - last_now);
    last_now = now;
    MissionTimes& t = report.times;
    t.total += dt;
    switch (waiting) {
      case Work::kNavigate:
        t.navigate += dt;
        break;
      case Work::kPlan:
        t.plan += dt;
        break;
      case Work::kExecute:
        t.execute += dt;
        break;
      case Work::kDrill:
        t.drill += dt;
        break;
      case Work::kNone:
        break;
    }
    account_step(dt);
  }

  void account_step(double dt) {
    if (waiting_step == Step::kNone || step_area >= report.areas.size()) return;
    AreaReport& a = report.areas[step_area];
    AreaTimes& at = a.times;
    HoleTimes* ht = step_hole < a.holes.size() ? &a.holes[step_hole].times : nullptr;
    switch (waiting_step) {
      case Step::kApproach:
        at.approach += dt;
        break;
      case Step::kDetect:
        at.detect += dt;
        break;
      case Step::kSurvey:
        at.survey += dt;
        break;
      case Step::kPlace:
        at.place += dt;
        break;
      case Step::kAlign:
        if (ht) ht->align += dt;
        break;
      case Step::kDrill:
        if (ht) ht->drill += dt;
        break;
      case Step::kRetract:
        if (ht) ht->retract += dt;
        break;
      case Step::kNone:
        break;
    }
  }
};

MissionTree::MissionTree(Mission mission, MissionPorts& ports)
    : impl_(std::make_unique<Impl>(std::move(mission), ports)) {}

MissionTree::~MissionTree() = default;

void MissionTree::resume(const MissionReport& previous) {
  Impl& m = *impl_;
  if (m.started) throw DrillError("resume(): mission '" + m.mission.name + "' has started already");
  if (previous.mission != m.mission.name) {
    throw DrillError("resume(): the report is of mission '" + previous.mission + "', not '" +
                     m.mission.name + "'");
  }
  for (std::size_t i = 0; i < m.report.areas.size(); ++i) {
    AreaReport& area = m.report.areas[i];
    const auto before = std::find_if(previous.areas.begin(), previous.areas.end(),
                                     [&](const AreaReport& a) { return a.name == area.name; });
    if (before == previous.areas.end()) continue;
    if (before->state == AreaState::kDone || before->state == AreaState::kSkipped) {
      area = *before;
      area.state = AreaState::kSkipped;
      area.reason = kDoneBefore;
      for (auto& hole : area.holes) {
        if (was_drilled(hole)) {
          hole.state = HoleState::kSkipped;
          hole.reason = kDrilledBefore;
        }
      }
      continue;
    }
    for (const auto& hole : before->holes) {
      if (was_drilled(hole)) m.drilled_before[i].push_back(hole.point.frame.translation());
    }
  }
}

MissionState MissionTree::tick(double now) {
  Impl& m = *impl_;
  if (m.finished()) return m.report.state;
  m.account(now);
  m.report.state = MissionState::kRunning;
  const Outcome health = m.ports.health();
  if (health.progress == Progress::kRunning) return m.report.state;  // not all heard yet
  if (health.progress != Progress::kSucceeded) {
    m.halt(MissionState::kAborted,
           "health: " + (health.reason.empty() ? std::string("not healthy") : health.reason));
    return m.report.state;
  }
  m.waiting = Work::kNone;
  m.waiting_step = Step::kNone;
  const bt::Status status = m.root->tick();
  if (!m.fatal.empty()) {
    m.ports.stop();
    m.finish(MissionState::kFailed, m.fatal);
  } else if (status != bt::Status::kRunning) {
    m.conclude();
  }
  return m.report.state;
}

void MissionTree::abort(const std::string& reason) {
  if (impl_->finished()) return;
  impl_->halt(MissionState::kAborted, reason);
}

MissionStatus MissionTree::status() const {
  const Impl& m = *impl_;
  return {.state = m.report.state,
          .active = m.finished() ? "" : bt::active_path(*m.root),
          .area = m.current_area,
          .hole = m.current_hole,
          .reason = m.report.reason};
}

const MissionReport& MissionTree::report() const { return impl_->report; }

std::string MissionTree::describe() const {
  std::string out;
  impl_->root->describe(out);
  return out;
}

}  // namespace concert::drill
