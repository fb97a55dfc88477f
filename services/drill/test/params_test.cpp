// The drill's parameter file: the shipped config/drill.yaml holds every default (each row of the
// tables too); bad values, unknown keys and broken rules across keys are refused naming the
// file, the key and the line. CONCERT_DRILL_CONFIG_DIR is services/drill/config.

#include "drill/params.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "drill/mission.hpp"

namespace concert::drill {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

const std::string kShipped = std::string(CONCERT_DRILL_CONFIG_DIR) + "/drill.yaml";

std::string error_of(const std::string& yaml) {
  try {
    (void)parse_params(yaml, "drill.yaml");
  } catch (const DrillError& e) {
    return e.what();
  }
  return "(no error)";
}

/// Every field of `a` and `b` alike (DrillParams and PlacementDraw have no operator==).
void expect_same(const Params& a, const Params& b) {
  EXPECT_EQ(a.camera.working_distance, b.camera.working_distance);
  EXPECT_EQ(a.camera.fov, b.camera.fov);
  EXPECT_EQ(a.camera.averaged_frames, b.camera.averaged_frames);
  EXPECT_EQ(a.camera.reanchor_frames, b.camera.reanchor_frames);
  EXPECT_EQ(a.buffers.sample_step, b.buffers.sample_step);
  EXPECT_EQ(a.buffers.samples, b.buffers.samples);
  EXPECT_EQ(a.buffers.frames, b.buffers.frames);
  EXPECT_EQ(a.liveness.service_lost, b.liveness.service_lost);
  EXPECT_EQ(a.liveness.joints_lost, b.liveness.joints_lost);
  EXPECT_EQ(a.liveness.robot_service, b.liveness.robot_service);
  EXPECT_EQ(a.plan_requests.ack_bound, b.plan_requests.ack_bound);
  EXPECT_EQ(a.plan_requests.resends, b.plan_requests.resends);
  EXPECT_EQ(a.rest.above, b.rest.above);
  EXPECT_EQ(a.rest.hold, b.rest.hold);
  EXPECT_EQ(a.rest.until, b.rest.until);
  EXPECT_EQ(a.rest.timeout, b.rest.timeout);
  EXPECT_EQ(a.thermal.fold_start, b.thermal.fold_start);
  EXPECT_EQ(a.thermal.fold_end, b.thermal.fold_end);
  EXPECT_EQ(a.approach.padding, b.approach.padding);
  EXPECT_EQ(a.approach.attempts, b.approach.attempts);
  EXPECT_EQ(a.approach.thrust_checked, b.approach.thrust_checked);
  EXPECT_EQ(a.bim.wall_standoff, b.bim.wall_standoff);
  EXPECT_EQ(a.bim.robot_radius, b.bim.robot_radius);
  EXPECT_EQ(a.hole.default_depth, b.hole.default_depth);
  EXPECT_EQ(a.hole.align_margin, b.hole.align_margin);
  EXPECT_EQ(a.hole.replan_shift, b.hole.replan_shift);
  EXPECT_EQ(a.hole.body_replans, b.hole.body_replans);
  EXPECT_EQ(a.hole.body_draws, b.hole.body_draws);
  EXPECT_EQ(a.hole.place_unseen, b.hole.place_unseen);
  EXPECT_EQ(a.hole.lightest_lead, b.hole.lightest_lead);
  ASSERT_EQ(a.hole.attempts.size(), b.hole.attempts.size());
  for (std::size_t i = 0; i < a.hole.attempts.size(); ++i) {
    const HoleAttempt& x = a.hole.attempts[i];
    const HoleAttempt& y = b.hole.attempts[i];
    EXPECT_EQ(x.reach, y.reach) << "hole.attempts[" << i << "]";
    EXPECT_EQ(x.fixed_base, y.fixed_base) << "hole.attempts[" << i << "]";
    EXPECT_EQ(x.base_travel, y.base_travel) << "hole.attempts[" << i << "]";
    EXPECT_EQ(x.further, y.further) << "hole.attempts[" << i << "]";
    EXPECT_EQ(x.lead, y.lead) << "hole.attempts[" << i << "]";
  }
  EXPECT_EQ(a.paths.settle_min, b.paths.settle_min);
  EXPECT_EQ(a.paths.base_kept, b.paths.base_kept);
  EXPECT_EQ(a.paths.joint_speed, b.paths.joint_speed);
  EXPECT_EQ(a.paths.base_speed, b.paths.base_speed);
  EXPECT_EQ(a.paths.speed_share, b.paths.speed_share);
  EXPECT_EQ(a.looks.marker_stale, b.looks.marker_stale);
  EXPECT_EQ(a.looks.marker_drift, b.looks.marker_drift);
  EXPECT_EQ(a.looks.look_force, b.looks.look_force);
  ASSERT_EQ(a.looks.attempts.size(), b.looks.attempts.size());
  for (std::size_t i = 0; i < a.looks.attempts.size(); ++i) {
    EXPECT_EQ(a.looks.attempts[i], b.looks.attempts[i]) << "looks.attempts[" << i << "]";
  }
  EXPECT_EQ(a.placement.last_hole_attempt, b.placement.last_hole_attempt);
  EXPECT_EQ(a.placement.light_lead, b.placement.light_lead);
  EXPECT_EQ(a.placement.look_further, b.placement.look_further);
  ASSERT_EQ(a.placement.draws.size(), b.placement.draws.size());
  for (std::size_t i = 0; i < a.placement.draws.size(); ++i) {
    const PlacementDraw& x = a.placement.draws[i];
    const PlacementDraw& y = b.placement.draws[i];
    EXPECT_EQ(x.out, y.out) << "placement.draws[" << i << "]";
    EXPECT_EQ(x.toward, y.toward) << "placement.draws[" << i << "]";
  }
  EXPECT_EQ(a.survey.tries, b.survey.tries);
  ASSERT_EQ(a.survey.attempts.size(), b.survey.attempts.size());
  for (std::size_t i = 0; i < a.survey.attempts.size(); ++i)
    EXPECT_EQ(a.survey.attempts[i], b.survey.attempts[i]) << "survey.attempts[" << i << "]";
  EXPECT_EQ(a.blobs.match, b.blobs.match);
  EXPECT_EQ(a.blobs.track_window, b.blobs.track_window);
  EXPECT_EQ(a.blobs.set_shift, b.blobs.set_shift);
  EXPECT_EQ(a.blobs.set_look_drift, b.blobs.set_look_drift);
  EXPECT_EQ(a.blobs.reanchor_distance, b.blobs.reanchor_distance);
  const DrillParams& m = a.motion;
  const DrillParams& n = b.motion;
  EXPECT_EQ(m.standoff, n.standoff);
  EXPECT_EQ(m.approach_speed, n.approach_speed);
  EXPECT_EQ(m.approach_turn, n.approach_turn);
  EXPECT_EQ(m.align_tolerance, n.align_tolerance);
  EXPECT_EQ(m.align_angle, n.align_angle);
  EXPECT_EQ(m.settle_time, n.settle_time);
  EXPECT_EQ(m.feed_rate, n.feed_rate);
  EXPECT_EQ(m.max_lead, n.max_lead);
  EXPECT_EQ(m.servo_jump, n.servo_jump);
  EXPECT_EQ(m.contact_lead, n.contact_lead);
  EXPECT_EQ(m.contact_search, n.contact_search);
  EXPECT_EQ(m.align_timeout, n.align_timeout);
  EXPECT_EQ(m.drill_timeout, n.drill_timeout);
  EXPECT_EQ(m.retract_timeout, n.retract_timeout);
  EXPECT_EQ(m.stiffness, n.stiffness);
  EXPECT_EQ(m.damping, n.damping);
  EXPECT_EQ(m.angular_stiffness, n.angular_stiffness);
  EXPECT_EQ(m.angular_damping, n.angular_damping);
}

TEST(DrillParamsFile, TheShippedFileHoldsEveryDefault) {
  config::Document doc = config::Document::load(kShipped);
  const Params p = read_params(doc);
  EXPECT_TRUE(doc.differences_from_defaults().empty())
      << ::testing::PrintToString(doc.differences_from_defaults());
  // Every key read: 65 single values (look_further one of them), the 4 tables' lengths, and
  // their rows' keys: 27 attempts x 5, 6 looks x 3, 3 draws x 2, 3 survey attempts x 5.
  EXPECT_EQ(doc.keys().size(), 65u + 4u + 27u * 5u + 6u * 3u + 3u * 2u + 3u * 5u);
  expect_same(p, Params{});
  expect_same(load_params(kShipped), Params{});
}

TEST(DrillParamsFile, TheDefaultsAreTheCodesConstants) {
  const Params d;
  EXPECT_EQ(d.hole.lightest_lead, kLightestLead);
  EXPECT_EQ(d.hole.attempts.size(), 27u);
  EXPECT_EQ(d.hole.attempts[14].lead, kLightestLead);
  ASSERT_EQ(d.placement.draws.size(), std::size(kPlacementDraws));
  for (std::size_t i = 0; i < d.placement.draws.size(); ++i) {
    EXPECT_EQ(d.placement.draws[i].out, kPlacementDraws[i].out);
    EXPECT_EQ(d.placement.draws[i].toward, kPlacementDraws[i].toward);
  }
  // An empty file is the defaults.
  expect_same(parse_params("", "drill.yaml"), d);
  // A key given changes that key alone; a table given replaces the whole table.
  const Params p = parse_params(
      "hole:\n  attempts:\n    - {further: 0.02}\n    - {reach: false, lead: 0.5}\n"
      "placement:\n  last_hole_attempt: 0\n  light_lead: 1.0\nmotion:\n  feed_rate: 0.008\n",
      "drill.yaml");
  EXPECT_EQ(p.hole.attempts,
            (std::vector<HoleAttempt>{{true, true, 0.0, 0.02, 1.0}, {false, true, 0.0, 0.0, 0.5}}));
  EXPECT_EQ(p.motion.feed_rate, 0.008);
  EXPECT_EQ(p.motion.max_lead, d.motion.max_lead);
}

TEST(DrillParamsFile, ABadValueNamesFileKeyAndLine) {
  EXPECT_EQ(error_of("hole:\n  attempts:\n    - {reach: true}\n    - {reach: true, further: x}\n"),
            "drill.yaml: hole.attempts[1].further: expected a number >= 0, got 'x' (line 4)");
  EXPECT_EQ(error_of("hole:\n  attempts:\n    - {lead: 0}\n"),
            "drill.yaml: hole.attempts[0].lead: expected a number in (0, 1], got '0' (line 3)");
  EXPECT_EQ(error_of("placement:\n  draws:\n    - {out: 0.2, toward: 2}\n"),
            "drill.yaml: placement.draws[0].toward: expected a number in [0, 1], got '2' (line 3)");
  EXPECT_EQ(error_of("looks:\n  attempts:\n    - {between: maybe}\n"),
            "drill.yaml: looks.attempts[0].between: expected true or false, got 'maybe' (line 3)");
  EXPECT_THAT(error_of("looks:\n  attempts:\n    - {between: true, further: 0.2, slant: 0.8}\n"),
              ::testing::HasSubstr("drill.yaml: looks.attempts[0].slant: a look centred between hole and marker"));
  EXPECT_THAT(error_of("looks:\n  attempts:\n    - {further: 0.8, slant: 2}\n"),
              ::testing::HasSubstr("drill.yaml: looks.attempts[0].slant: expected a number in [0, 1.4], got '2'"));
  EXPECT_EQ(error_of("hole:\n  attempts: 3\n"),
            "drill.yaml: hole.attempts: expected a list of maps, got '3' (line 2)");
  EXPECT_EQ(error_of("buffers:\n  frames: 0\n"),
            "drill.yaml: buffers.frames: expected a whole number from 1 to 1000, got '0' (line "
            "2)");
  EXPECT_EQ(error_of("camera:\n  working_distance: 0.6\n  fov: 55\n"),
            "drill.yaml: camera.fov: expected a number in (0, 3.141592653589793], got '55' "
            "(line 3)");
  EXPECT_EQ(error_of("motion:\n  stiffness: -1\n"),
            "drill.yaml: motion.stiffness: expected a positive number, got '-1' (line 2)");
  EXPECT_EQ(error_of("paths: 1\n"),
            "drill.yaml: paths: expected a map of parameters, got '1' (line 1)");

  // From a file: its path named.
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / "concert_drill_params_test.yaml";
  std::ofstream(file) << "liveness:\n  service_lost: soon\n";
  try {
    (void)load_params(file);
    ADD_FAILURE() << "no error for a bad value";
  } catch (const DrillError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() +
                                         ": liveness.service_lost: expected a positive number, got "
                                         "'soon' (line 2)");
  }
  std::filesystem::remove(file);
  EXPECT_THROW((void)load_params(file), DrillError);
}

TEST(DrillParamsFile, AnUnknownKeyIsRefusedNamingIt) {
  EXPECT_EQ(error_of("hole:\n  atempts: []\n"),
            "drill.yaml: hole.atempts: unknown key (line 2); known keys of hole: align_margin, "
            "attempts, body_draws, body_replans, default_depth, lightest_lead, place_unseen, "
            "replan_shift");
  EXPECT_EQ(error_of("looks:\n  attempts:\n    - {between: false, furthr: 0.1}\n"),
            "drill.yaml: looks.attempts[0].furthr: unknown key (line 3); known keys of "
            "looks.attempts[0]: between, further, slant");
  EXPECT_EQ(error_of("cameras: {}\n"),
            "drill.yaml: cameras: unknown key (line 1); known keys: approach, bim, blobs, buffers, "
            "camera, hole, liveness, looks, motion, paths, placement, plan_requests, rest, survey, thermal");
  EXPECT_THAT(error_of("motion:\n  feed: 0.01\n"),
              StartsWith("drill.yaml: motion.feed: unknown key (line 2); known keys of motion: "));
}

TEST(DrillParamsFile, ABrokenRuleAcrossKeysIsRefused) {
  // A hole's search and a placement's checks start at the first attempt.
  EXPECT_EQ(error_of("hole:\n  attempts: []\n"),
            "drill.yaml: hole.attempts: expected at least one attempt: a hole's first posture "
            "request (line 2)");
  EXPECT_THAT(error_of("hole:\n  attempts:\n    - {reach: true, fixed_base: false}\n"),
              AllOf(StartsWith("drill.yaml: hole.attempts[0].fixed_base: the first attempt must "
                               "check the reach with the arm alone"),
                    HasSubstr("(line 3)")));
  // The attempts a placement checks: in the table, arm alone, reach checked, full thrust.
  EXPECT_EQ(error_of("placement:\n  last_hole_attempt: 27\n"),
            "drill.yaml: placement.last_hole_attempt: expected an index of hole.attempts (0 to "
            "26) (line 2)");
  EXPECT_THAT(error_of("placement:\n  last_hole_attempt: 3\n"),
              AllOf(StartsWith("drill.yaml: placement.last_hole_attempt: hole.attempts[3]."
                               "fixed_base: a placement checks hole.attempts[0..3]"),
                    HasSubstr("(line 2)")));
  // The row itself is named when the file gives the table.
  EXPECT_THAT(error_of("hole:\n  attempts:\n    - {}\n    - {further: 0.03, lead: 0.5}\n"
                       "    - {further: 0.07}\n"),
              AllOf(StartsWith("drill.yaml: hole.attempts[1].lead: a placement checks "
                               "hole.attempts[0..2]"),
                    HasSubstr("(line 4)")));
  // A placement checked again at a light lead starts at an arm-alone attempt at that lead.
  EXPECT_THAT(error_of("placement:\n  light_lead: 0.6\n"),
              AllOf(StartsWith("drill.yaml: placement.light_lead: no attempt of hole.attempts "
                               "checks the reach with the arm alone at this lead"),
                    HasSubstr("(line 2)")));
  // Leads whose checked thrusts coincide (light_drilling's floor): a thrust no longer tells
  // its lead.
  EXPECT_THAT(error_of("placement:\n  last_hole_attempt: 0\n  light_lead: 0.35\nhole:\n"
                       "  attempts:\n    - {}\n    - {lead: 0.35}\n    - {lead: 0.3}\n"),
              AllOf(StartsWith("drill.yaml: hole.attempts[2].lead: gives the same checked "
                               "thrust ("),
                    HasSubstr("as hole.attempts[1]'s lead 0.35"), HasSubstr("(line 8)")));
  EXPECT_THAT(error_of("motion:\n  contact_lead: 0.006\n"),
              StartsWith("drill.yaml: motion: hole.attempts[14].lead: gives the same checked "
                         "thrust ("));
  EXPECT_EQ(error_of("motion:\n  max_lead: 0.004\n"),
            "drill.yaml: motion.max_lead: must exceed motion.contact_lead (0.004): the reference "
            "must lead the bit that far for it to feel the wall (line 2)");
  // Tables a search starts from may not be empty.
  EXPECT_EQ(error_of("looks:\n  attempts: []\n"),
            "drill.yaml: looks.attempts: expected at least one look: a hole's looks start there "
            "(line 2)");
  EXPECT_THAT(error_of("placement:\n  look_further: []\n"),
              StartsWith("drill.yaml: placement.look_further: expected at least one distance"));
  EXPECT_THAT(error_of("placement:\n  draws: []\n"),
              StartsWith("drill.yaml: placement.draws: expected at least one draw"));
  // A rest ends below where it starts.
  EXPECT_EQ(error_of("rest:\n  above: 0.8\n  until: 0.8\n"),
            "drill.yaml: rest.until: expected below rest.above (0.8): a rest ends when the arm is "
            "cooler than a rest starts at (line 3)");
  EXPECT_EQ(error_of("thermal:\n  fold_end: 0.9\n"),
            "drill.yaml: thermal.fold_end: expected above thermal.fold_start (0.95): the thrust folds "
            "back between them (line 2)");
  // An averaged view needs that many frames kept.
  EXPECT_EQ(error_of("buffers:\n  frames: 4\n"),
            "drill.yaml: buffers.frames: expected at least camera.averaged_frames and "
            "camera.reanchor_frames (5): an averaged view takes the newest frames kept (line 2)");
}

}  // namespace
}  // namespace concert::drill
