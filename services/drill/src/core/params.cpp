// Reads the drill service's parameter file (config/drill.yaml lists every key with its default)
// with libs/config, then checks the rules across keys the mission relies on.
#include "drill/params.hpp"

#include <sstream>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "drill/mission.hpp"

namespace concert::drill {
namespace {

using config::Map;
using config::Range;

/// A lead's fraction: (0, 1].
const Range kLead{0.0, 1.0, true};

std::string text(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

void read_camera(Map m, Params::Camera& c) {
  m.number("working_distance", c.working_distance, Range::positive());
  m.number("fov", c.fov, Range{0.0, std::numbers::pi, true});
  m.integer("averaged_frames", c.averaged_frames, 1, 100);
  m.integer("reanchor_frames", c.reanchor_frames, 1, 100);
}

void read_buffers(Map m, Params::Buffers& b) {
  m.duration("sample_step", b.sample_step, Range::between(0.0, 1.0));
  m.integer("samples", b.samples, 1, 1'000'000);
  m.integer("frames", b.frames, 1, 1000);
}

void read_service_bounds(Map liveness, Map plan_requests, Map approach, Map bim, Params& p) {
  liveness.number("service_lost", p.liveness.service_lost, Range::positive());
  liveness.number("joints_lost", p.liveness.joints_lost, Range::positive());
  liveness.string("robot_service", p.liveness.robot_service, false);
  plan_requests.number("ack_bound", p.plan_requests.ack_bound, Range::positive());
  plan_requests.integer("resends", p.plan_requests.resends, 0, 1000);
  approach.number("padding", p.approach.padding, Range::non_negative());
  approach.integer("attempts", p.approach.attempts, 1, 1000);
  approach.number("thrust_checked", p.approach.thrust_checked, Range::positive());
  bim.number("wall_standoff", p.bim.wall_standoff, Range::positive());
  bim.number("robot_radius", p.bim.robot_radius, Range::positive());
}

void read_rest(Map m, Params::Rest& r) {
  m.number("above", r.above, Range::positive());
  m.number("hold", r.hold, Range::positive());
  m.number("until", r.until, Range::positive());
  m.number("timeout", r.timeout, Range::non_negative());
  if (r.until >= r.above) {
    std::ostringstream what;
    what << "expected below rest.above (" << r.above
         << "): a rest ends when the arm is cooler than a rest starts at";
    m.fail("until", what.str());
  }
}

void read_thermal(Map m, Params::Thermal& t) {
  m.number("fold_start", t.fold_start, Range::positive());
  m.number("fold_end", t.fold_end, Range::positive());
  if (t.fold_end <= t.fold_start) {
    std::ostringstream what;
    what << "expected above thermal.fold_start (" << t.fold_start << "): the thrust folds back between them";
    m.fail("fold_end", what.str());
  }
}

void read_attempt(Map& item, HoleAttempt& a) {
  item.boolean("reach", a.reach);
  item.boolean("fixed_base", a.fixed_base);
  item.number("base_travel", a.base_travel, Range::non_negative());
  item.number("further", a.further, Range::non_negative());
  item.number("lead", a.lead, kLead);
}

/// Reads the hole section; returns the items of hole.attempts (none when the file leaves the
/// list out) for the rules across keys.
std::vector<Map> read_hole(Map m, Params::Hole& h) {
  m.number("default_depth", h.default_depth, Range::positive());
  m.number("align_margin", h.align_margin, Range::non_negative());
  m.number("replan_shift", h.replan_shift, Range::non_negative());
  m.integer("body_replans", h.body_replans, 0, 100);
  m.integer("body_draws", h.body_draws, 1, 100);
  m.boolean("place_unseen", h.place_unseen);
  m.number("lightest_lead", h.lightest_lead, kLead);
  return m.sequence("attempts", h.attempts, read_attempt);
}

void read_survey(Map m, Params::Survey& s) {
  m.sequence("attempts", s.attempts, read_attempt);
  m.integer("tries", s.tries, 1, 100);
}

void read_paths(Map m, Params::Paths& p) {
  m.number("settle_min", p.settle_min, Range::positive());
  // 0 would keep the base however far it stands (keep_base's bound 0: unbounded).
  m.number("base_kept", p.base_kept, Range::positive());
  m.number("joint_speed", p.joint_speed, Range::positive());
  m.number("base_speed", p.base_speed, Range::positive());
  m.number("speed_share", p.speed_share, Range::positive());
}

void read_looks(Map m, Params::Looks& l) {
  m.number("marker_stale", l.marker_stale, Range::non_negative());
  m.number("marker_drift", l.marker_drift, Range::non_negative());
  m.number("look_force", l.look_force, Range::positive());
  m.sequence("attempts", l.attempts, [](Map& item, LookAttempt& a) {
    item.boolean("between", a.between);
    item.number("further", a.further, Range::non_negative());
    item.number("slant", a.slant, Range::between(0.0, 1.4));
    if (a.between && a.slant > 0.0)
      item.fail("slant", "a look centred between hole and marker is on the wall's normal: slant must be 0 with between");
  });
}

void read_placement(Map m, Params::Placement& p) {
  m.integer("last_hole_attempt", p.last_hole_attempt, 0, 1000);
  m.number("light_lead", p.light_lead, kLead);
  m.numbers("look_further", p.look_further, 0, Range::non_negative());
  m.sequence("draws", p.draws, [](Map& item, PlacementDraw& d) {
    item.number("out", d.out, Range::non_negative());
    item.number("toward", d.toward, Range::between(0.0, 1.0));
  });
}

void read_blobs(Map m, Params::Blobs& b) {
  m.number("match", b.match, Range::positive());
  m.number("track_window", b.track_window, Range::positive());
  m.number("set_shift", b.set_shift, Range::positive());
  m.number("set_look_drift", b.set_look_drift, Range::non_negative());
  m.number("reanchor_distance", b.reanchor_distance, Range::positive());
}

void read_motion(Map m, DrillParams& d) {
  const std::pair<const char*, double*> positive[] = {
      {"standoff", &d.standoff},
      {"approach_speed", &d.approach_speed},
      {"approach_turn", &d.approach_turn},
      {"align_tolerance", &d.align_tolerance},
      {"align_angle", &d.align_angle},
      {"feed_rate", &d.feed_rate},
      {"max_lead", &d.max_lead},
      {"servo_jump", &d.servo_jump},
      {"contact_lead", &d.contact_lead},
      {"contact_search", &d.contact_search},
      {"align_timeout", &d.align_timeout},
      {"drill_timeout", &d.drill_timeout},
      {"retract_timeout", &d.retract_timeout},
      {"stiffness", &d.stiffness},
      {"angular_stiffness", &d.angular_stiffness},
  };
  const std::pair<const char*, double*> non_negative[] = {
      {"settle_time", &d.settle_time},
      {"damping", &d.damping},
      {"angular_damping", &d.angular_damping},
  };
  for (const auto& [key, value] : positive) m.number(key, *value, Range::positive());
  for (const auto& [key, value] : non_negative) m.number(key, *value, Range::non_negative());
}

/// The force the planner checks a posture drilled at `lead` with (the node's checked_thrust).
double checked_thrust(const Params& p, double lead) {
  return p.approach.thrust_checked * thrust_bound(light_drilling(p.motion, lead));
}

/// The sections the rules across keys name (kept from the reading: their lines).
struct Sections {
  Map root;
  Map buffers;
  Map hole;
  Map looks;
  Map placement;
  Map survey;
  Map motion;
};

/// Attempt `i`'s `key` is wrong: named in its item when the file lists the attempts, else at
/// `other_key` of `other` (the key elsewhere that made the default table wrong).
[[noreturn]] void attempt_fails(const std::vector<Map>& rows, std::size_t i, std::string_view key,
                                const Map& other, std::string_view other_key,
                                const std::string& what) {
  if (i < rows.size()) rows[i].fail(key, what);
  other.fail(other_key,
             "hole.attempts[" + std::to_string(i) + "]." + std::string(key) + ": " + what);
}

/// The rules on hole.attempts: where a hole's search and a placement's checks start, and that a
/// posture's checked thrust tells its lead (the node's lead_checked matches on it).
void check_attempts(const Params& p, const std::vector<Map>& rows, const Sections& at) {
  const std::vector<HoleAttempt>& a = p.hole.attempts;
  if (a.empty()) {
    at.hole.fail("attempts", "expected at least one attempt: a hole's first posture request");
  }
  if (!a[0].reach || !a[0].fixed_base) {
    attempt_fails(rows, 0, a[0].reach ? "fixed_base" : "reach", at.hole, "attempts",
                  "the first attempt must check the reach with the arm alone (reach and "
                  "fixed_base true): a hole's posture search and a placement's checks start there");
  }
  const std::size_t last = p.placement.last_hole_attempt;
  if (last >= a.size()) {
    at.placement.fail("last_hole_attempt", "expected an index of hole.attempts (0 to " +
                                               std::to_string(a.size() - 1) + ")");
  }
  for (std::size_t i = 0; i <= last; ++i) {
    const char* key = !a[i].reach        ? "reach"
                      : !a[i].fixed_base ? "fixed_base"
                      : a[i].lead != 1.0 ? "lead"
                                         : nullptr;
    if (key) {
      attempt_fails(rows, i, key, at.placement, "last_hole_attempt",
                    "a placement checks hole.attempts[0.." + std::to_string(last) +
                        "] (placement.last_hole_attempt): each must check the reach with the "
                        "arm alone at lead 1");
    }
  }
  const bool light = std::any_of(a.begin(), a.end(), [&](const HoleAttempt& h) {
    return h.reach && h.fixed_base && h.lead == p.placement.light_lead;
  });
  if (!light) {
    at.placement.fail("light_lead",
                      "no attempt of hole.attempts checks the reach with the arm alone at this "
                      "lead: a placement checked at it starts its holes there");
  }
  for (std::size_t j = 1; j < a.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      if (a[i].lead == a[j].lead) continue;
      const double t = checked_thrust(p, a[j].lead);
      if (std::abs(checked_thrust(p, a[i].lead) - t) >= 1e-6) continue;
      const std::string what =
          "gives the same checked thrust (" + text(t) + " N) as hole.attempts[" +
          std::to_string(i) + "]'s lead " + text(a[i].lead) +
          " (light_drilling keeps the lead above motion.contact_lead): a posture's checked "
          "thrust must tell its lead";
      attempt_fails(rows, j, "lead", at.root, "motion", what);
    }
  }
}

/// The rules across keys the mission relies on; each names a key of the file and its line.
void check_rules(const Params& p, const std::vector<Map>& rows, const Sections& at) {
  // The bit feels the wall when the reference leads it by contact_lead; max_lead bounds the lead.
  if (p.motion.max_lead <= p.motion.contact_lead) {
    at.motion.fail("max_lead", "must exceed motion.contact_lead (" + text(p.motion.contact_lead) +
                                   "): the reference must lead the bit that far for it to feel "
                                   "the wall");
  }
  check_attempts(p, rows, at);
  if (p.looks.attempts.empty()) {
    at.looks.fail("attempts", "expected at least one look: a hole's looks start there");
  }
  if (p.placement.look_further.empty()) {
    at.placement.fail("look_further",
                      "expected at least one distance: a placement's look starts there");
  }
  if (p.survey.attempts.empty()) {
    at.survey.fail("attempts", "expected at least one attempt: a hole's reach is judged by them");
  }
  if (p.placement.draws.empty()) {
    at.placement.fail("draws", "expected at least one draw: a placement draws one posture or more");
  }
  // An averaged view takes the newest frames kept: with fewer kept it never comes.
  const auto most =
      static_cast<std::size_t>(std::max(p.camera.averaged_frames, p.camera.reanchor_frames));
  if (p.buffers.frames < most) {
    at.buffers.fail("frames", "expected at least camera.averaged_frames and "
                              "camera.reanchor_frames (" +
                                  std::to_string(most) +
                                  "): an averaged view takes the newest frames kept");
  }
}

}  // namespace

Params read_params(config::Document& doc) {
  Params p;
  Map root = doc.root();
  const Sections at{root,
                    root.section("buffers"),
                    root.section("hole"),
                    root.section("looks"),
                    root.section("placement"),
                    root.section("survey"),
                    root.section("motion")};
  read_camera(root.section("camera"), p.camera);
  read_buffers(at.buffers, p.buffers);
  const Map liveness = root.section("liveness");
  const Map plan_requests = root.section("plan_requests");
  const Map approach = root.section("approach");
  read_service_bounds(liveness, plan_requests, approach, root.section("bim"), p);
  const std::vector<Map> rows = read_hole(at.hole, p.hole);
  read_paths(root.section("paths"), p.paths);
  read_looks(at.looks, p.looks);
  read_placement(at.placement, p.placement);
  read_survey(at.survey, p.survey);
  read_blobs(root.section("blobs"), p.blobs);
  read_rest(root.section("rest"), p.rest);
  read_thermal(root.section("thermal"), p.thermal);
  read_motion(at.motion, p.motion);
  doc.finish();
  check_rules(p, rows, at);
  return p;
}

Params parse_params(const std::string& yaml, const std::string& source) {
  try {
    return config::Document::parse(yaml, source).read_with(read_params);
  } catch (const config::ConfigError& e) {
    throw DrillError(e.what());
  }
}

Params load_params(const std::filesystem::path& file) {
  try {
    return config::Document::load(file).read_with(read_params);
  } catch (const config::ConfigError& e) {
    throw DrillError(e.what());
  }
}

}  // namespace concert::drill
