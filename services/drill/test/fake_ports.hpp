#pragma once
// A scriptable MissionPorts for the mission tree's tests. It records every call that starts
// something (and stop()) as a string, runs each operation for a scripted time of its own clock,
// then lets it succeed or fail as scripted, and checks what the real robot would object to: a
// poll with nothing started, and a trajectory executed from somewhere else than where it was
// planned from.
//
//   FakePorts fake(3);                                // 3 areas, 2 blobs each, no base pose
//   fake.areas[1].base = BasePose{1.0, 0.0, 0.0};     // area 1 is a BIM wall area
//   fake.scripts["drill 0 blob 2"] = {4.0, "bit stalled"};
//   run(tree, fake);                                  // ticks at 0, 1, 2, ... s until done
//
// Calls: "resolve I", "navigate I" (I: the area whose base pose it is), "plan I after J|none",
// "execute I", "detect I", "survey I N" (N: the holes asked about), "place I N" (N: the holes to
// place for), "align I LABEL",
// "drill I LABEL DEPTH", "retract I LABEL", "stow", "stop".

#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "drill/mission_tree.hpp"
#include "drill/ports.hpp"

namespace concert::drill::testing {

/// How one operation goes: it runs `seconds` of the fake's clock after its start, then
/// succeeds, or fails with `fail` when that is not empty.
struct Script {
  double seconds{0.0};
  std::string fail;
};

class FakePorts : public MissionPorts {
 public:
  /// `n` areas: area i centred at (i, 0, 1) m, no base pose, with two blobs 5 cm right and left
  /// of its centre.
  explicit FakePorts(std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      ResolvedArea area;
      area.frame.translation() = Eigen::Vector3d(static_cast<double>(i), 0.0, 1.0);
      areas.push_back(area);
      points.push_back({blob(area, 1, 0.05), blob(area, 2, -0.05)});
    }
  }

  /// A blob `x` m right of the area's centre, labelled "blob K".
  static DrillPoint blob(const ResolvedArea& area, int k, double x) {
    DrillPoint p;
    p.frame = area.frame * Eigen::Translation3d(x, 0.0, 0.0);
    p.label = "blob " + std::to_string(k);
    p.servo = true;
    return p;
  }

  double now{0.0};                                  ///< the clock the tree is ticked with [s]
  std::vector<std::string> calls;                   ///< what was started, in order
  std::map<std::string, Script> scripts;            ///< by call
  double default_seconds{0.0};                      ///< how long the unscripted calls run [s]
  std::vector<ResolvedArea> areas;                  ///< what resolution() finds, per area
  std::vector<std::vector<DrillPoint>> points;      ///< what detection() finds, per area
  std::vector<std::size_t> placement_order;          ///< what placement() says (empty: as given)
  /// What classification() says of a hole, by "AREA LABEL" (others: reachable at full thrust).
  std::map<std::string, HoleReach> verdicts;
  std::string unhealthy;                            ///< health() fails with this when set
  std::function<void(const std::string&)> on_call;  ///< called after each recorded call
  std::vector<std::string> violations;              ///< what the robot would have refused
  int health_checks{0};
  int unheard_checks{0};  ///< health() is kRunning (a service not heard yet) this many times

  Outcome health() override {
    ++health_checks;
    if (unheard_checks > 0) {
      --unheard_checks;
      return Outcome::running();
    }
    return unhealthy.empty() ? Outcome::succeeded() : Outcome::failed(unhealthy);
  }

  void resolve(std::size_t area, const AreaSpec&) override {
    resolving_[area] = start("resolve " + std::to_string(area));
  }
  Outcome resolution(std::size_t area, ResolvedArea& out) override {
    Outcome o = poll(resolving_[area]);
    if (o.progress == Progress::kSucceeded) out = areas.at(area);
    return o;
  }

  void navigate(const BasePose& goal) override {
    std::size_t area = 0;
    while (area < areas.size() &&
           !(areas[area].base && areas[area].base->x == goal.x && areas[area].base->y == goal.y)) {
      ++area;
    }
    navigation_ = start("navigate " + std::to_string(area));
    posture_ = "base moved to area " + std::to_string(area);
  }
  Outcome navigation() override { return poll(navigation_); }

  void plan(std::size_t area, const Eigen::Isometry3d& frame,
            std::optional<std::size_t> after) override {
    if (!frame.isApprox(areas.at(area).frame)) violations.push_back("plan: wrong frame");
    planning_[area] = start("plan " + std::to_string(area) + " after " +
                            (after ? std::to_string(*after) : std::string("none")));
    plan_from_[area] = after ? "area " + std::to_string(*after) : posture_;
  }
  Outcome planning(std::size_t area) override { return poll(planning_[area]); }

  void execute(std::size_t area) override {
    const std::string call = "execute " + std::to_string(area);
    if (plan_from_[area] != posture_) {
      violations.push_back(call + ": planned from '" + plan_from_[area] +
                           "' but the robot is at '" + posture_ + "'");
    }
    executing_ = area;
    execution_ = start(call);
  }
  Outcome execution() override {
    Outcome o = poll(execution_);
    if (o.progress == Progress::kSucceeded) posture_ = "area " + std::to_string(executing_);
    if (o.progress == Progress::kFailed)
      posture_ = "on the way to area " + std::to_string(executing_);
    return o;
  }

  void detect(std::size_t area, const AreaSpec&, const ResolvedArea&) override {
    detecting_ = area;
    detection_ = start("detect " + std::to_string(area));
  }
  Outcome detection(std::vector<DrillPoint>& found) override {
    Outcome o = poll(detection_);
    if (o.progress == Progress::kSucceeded) found = points.at(detecting_);
    return o;
  }

  void classify(std::size_t area, const std::vector<DrillPoint>& holes) override {
    surveyed_ = holes;
    survey_ = start("survey " + std::to_string(area) + " " + std::to_string(holes.size()));
  }
  Outcome classification(std::vector<HoleReach>& reach) override {
    const Outcome o = poll(survey_);
    if (o.progress != Progress::kSucceeded) return o;
    reach.clear();
    for (const DrillPoint& p : surveyed_) {
      const auto v = verdicts.find(std::to_string(detecting_) + " " + p.label);
      reach.push_back(v == verdicts.end() ? HoleReach{Reach::kReachable, "at full thrust"} : v->second);
    }
    return o;
  }

  void place(std::size_t area, const std::vector<DrillPoint>& holes) override {
    placing_ = start("place " + std::to_string(area) + " " + std::to_string(holes.size()));
  }
  Outcome placement(std::vector<std::size_t>& order) override {
    const Outcome o = poll(placing_);
    if (o.progress == Progress::kSucceeded) order = placement_order;
    return o;
  }

  void align(const DrillPoint& point) override {
    label_ = std::to_string(detecting_) + " " + point.label;
    alignment_ = start("align " + label_);
  }
  Outcome alignment() override { return poll(alignment_); }

  void drill(const DrillPoint&, double depth) override {
    char d[16];
    std::snprintf(d, sizeof d, "%.3f", depth);
    drilling_ = start("drill " + label_ + " " + d);
  }
  Outcome drilling() override { return poll(drilling_); }

  void retract() override { retraction_ = start("retract " + label_); }
  Outcome retraction() override { return poll(retraction_); }

  void stow() override {
    stowing_ = start("stow");
    posture_ = "home";
  }
  Outcome stowing() override { return poll(stowing_); }

  void stop() override { record("stop"); }

  /// The calls that start with `prefix`.
  std::vector<std::string> calls_of(const std::string& prefix) const {
    std::vector<std::string> out;
    for (const auto& c : calls) {
      if (c.rfind(prefix, 0) == 0) out.push_back(c);
    }
    return out;
  }
  /// Index of `call` in calls (calls.size() if never made).
  std::size_t index_of(const std::string& call) const {
    std::size_t i = 0;
    while (i < calls.size() && calls[i] != call) ++i;
    return i;
  }

 private:
  struct Running {
    std::string call;  // empty: nothing started
    double until{0.0};
    std::string fail;
  };

  void record(const std::string& call) {
    calls.push_back(call);
    if (on_call) on_call(call);
  }
  Running start(const std::string& call) {
    record(call);
    const auto s = scripts.find(call);
    const Script script = s == scripts.end() ? Script{default_seconds, ""} : s->second;
    return {call, now + script.seconds, script.fail};
  }
  Outcome poll(const Running& op) {
    if (op.call.empty()) {
      violations.push_back("a poll with nothing started");
      return Outcome::failed("nothing started");
    }
    if (now < op.until) return Outcome::running();
    return op.fail.empty() ? Outcome::succeeded() : Outcome::failed(op.fail);
  }

  std::map<std::size_t, Running> resolving_, planning_;
  std::map<std::size_t, std::string> plan_from_;
  std::vector<DrillPoint> surveyed_;
  Running navigation_, execution_, detection_, survey_, placing_, alignment_, drilling_, retraction_, stowing_;
  std::size_t executing_{0}, detecting_{0};
  std::string label_;
  std::string posture_{"start"};
};

/// Ticks `tree` at the fake's clock, then `step` s later, and so on, until the mission ends or
/// `max_ticks` ticks passed; returns the last state. The clock stays at the last tick.
inline MissionState run(MissionTree& tree, FakePorts& fake, int max_ticks = 1000,
                        double step = 1.0) {
  MissionState state = tree.tick(fake.now);
  for (int k = 1; k < max_ticks && state == MissionState::kRunning; ++k) {
    fake.now += step;
    state = tree.tick(fake.now);
  }
  return state;
}

}  // namespace concert::drill::testing
