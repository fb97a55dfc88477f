#pragma once
// The drill service's tuning, read from its parameter file (config/drill.yaml lists every key
// with its default): how long it waits for the other services, what it keeps of the robot's and
// the camera's streams, what it asks the planner for and in which order (a hole's drilling
// postures, the looks at its mark, an area's base placement), how it matches blobs across the
// odometry's drift, and the drilling motion. The defaults are the values the missions were
// measured with; services/drill/README.md (Parameters) tells what was measured. Plain C++, no DDS.

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include "concert/config/config.hpp"
#include "drill/drill_motion.hpp"
#include "drill/placement.hpp"

namespace concert::drill {

/// One drilling posture a hole asks the planner for: the bit's tip on the hole's axis.
struct HoleAttempt {
  /// The arm's torques also checked with the bit at the hole's depth (PlanRequest.tip_reach).
  bool reach{true};
  /// The arm alone (the base stays where it stands); false: the whole body.
  bool fixed_base{true};
  /// [m, rad] the whole body's base moves and turns at most this much; 0: anywhere.
  double base_travel{0.0};
  /// [m] the bit this much beyond the hole's distance (motion.standoff + hole.align_margin).
  double further{0.0};
  /// Fraction of motion.max_lead drilled with (light_drilling), the torques checked at its thrust.
  double lead{1.0};

  bool operator==(const HoleAttempt&) const = default;
};

/// One look at a hole's mark after the base moved.
struct LookAttempt {
  /// The camera centred between the hole and its marker (both in view), not on the mark.
  bool between{false};
  /// [m] the camera this much beyond its distance at the hole's posture (with slant: at most).
  double further{0.0};
  /// [rad] > 0: the camera sees the mark from any side within this of the wall's normal, as
  /// near as frames the mark and at most `further` beyond the hole's distance
  /// (PlanRequest.view_slant); a marker hole's look only, not with `between`.
  double slant{0.0};

  bool operator==(const LookAttempt&) const = default;
};

/// Every tuning value of the drill service; the defaults are the shipped drill.yaml's.
struct Params {
  /// The drill camera and the views averaged from it.
  struct Camera {
    /// [m] camera to wall at an approach (planner's camera_distance); with fov, an area's radius.
    double working_distance{0.6};
    /// [rad] the camera's smaller field of view, used until a frame's intrinsics give it.
    double fov{55.0 * std::numbers::pi / 180.0};
    /// Depth frames averaged to locate an area and detect its holes (one frame is too noisy).
    int averaged_frames{5};
    /// Depth frames averaged to measure a hole again from a drilling or look posture.
    int reanchor_frames{3};
  };

  /// What is kept of the robot's and the camera's streams.
  struct Buffers {
    /// Joint states kept at most one per this (200 Hz); a frame is posed with the newest before it.
    std::chrono::nanoseconds sample_step{5'000'000};
    /// Joint samples kept (2 s at sample_step): a frame's stamp must fall among them.
    std::size_t samples{400};
    /// Camera frames kept, enough for the largest averaged view.
    std::size_t frames{12};
  };

  /// When another service counts as gone.
  struct Liveness {
    /// [s] a service's status older than this: lost (they beat every 1 s); a mission's start grace.
    double service_lost{5.0};
    /// [s] joint states older than this: the mission waits (decides nothing on stale joints)
    /// while the robot service's status still beats, and fails once they are older than
    /// service_lost or the robot's status is lost too.
    double joints_lost{1.0};
    /// The robot service's name in the service status (its `node.service_name`).
    std::string robot_service{"robot"};
  };

  /// Plan requests not acknowledged (one written before the planner's reader matched is lost).
  struct PlanRequests {
    /// [s] a request without PLANNING after this is sent again under the same id.
    double ack_bound{2.0};
    /// Resends at most; after them the answer is waited for.
    int resends{5};
  };

  /// An area's approach plan.
  struct Approach {
    /// [m] robot shapes grown against the map: odometry drifts 4-6 cm over a whole-body move.
    double padding{0.10};
    /// Plans in all (each with a new seed) when none was found within the planner's budget. A
    /// cold planner (no posture remembered for the model) finds the demo robot's approach to
    /// the house's areas at 1.3 m in 10 of 16 requests (a1) and 8 of 16 (c1): with 3 attempts a
    /// shift of 6 approaches failed one about every third shift; each failed request costs the
    /// planner's 2 s of CPU.
    int attempts{8};
    /// Torques checked at this times thrust_bound: the load while drilling exceeds the model's.
    double thrust_checked{1.6};
  };

  /// An area on a wall of the BIM model (bim::wall_goal).
  struct Bim {
    /// [m] the base pose's centre from the wall's face.
    double wall_standoff{1.05};
    /// [m] radius of the disc around the base pose that must be free in the storey's map.
    double robot_radius{0.55};
  };

  /// A hole's drilling posture.
  struct Hole {
    /// [m] the depth the bit's reach is checked to when no mission gives one.
    double default_depth{0.05};
    /// [m] the posture leaves the bit this far beyond motion.standoff; the alignment does the rest.
    double align_margin{0.03};
    /// [m] a hole measured again this far from its planned posture gets its posture planned again.
    double replan_shift{0.01};
    /// Whole-body postures planned again for a re-measured hole (each move drifts odometry again).
    std::size_t body_replans{2};
    /// Whole-body postures drawn for a marker hole until one lets the camera see its marker.
    std::size_t body_draws{3};
    /// A marker hole none of whose whole-body postures drawn lets the camera see the marker: the
    /// base placed for it alone (as an area's placement: from further out, with a look at the
    /// marker), instead of drilling it where odometry puts it.
    bool place_unseen{true};
    /// Lead drilled with when the alignment must reach past the posture checked (the least thrust).
    double lightest_lead{kLightestLead};
    /// Postures in the order asked: the base moves as little as it can, full thrust before lighter.
    std::vector<HoleAttempt> attempts{
        {true, true, 0.0, 0.0, 1.0},      {true, true, 0.0, 0.03, 1.0},
        {true, true, 0.0, 0.07, 1.0},     {true, false, 0.3, 0.0, 1.0},
        {true, false, 0.3, 0.03, 1.0},    {true, false, 0.3, 0.07, 1.0},
        {true, false, 0.0, 0.0, 1.0},     {true, false, 0.0, 0.07, 1.0},
        {true, true, 0.0, 0.0, 0.5},      {true, true, 0.0, 0.03, 0.5},
        {true, true, 0.0, 0.07, 0.5},     {true, false, 0.3, 0.0, 0.5},
        {true, false, 0.3, 0.07, 0.5},    {true, false, 0.0, 0.0, 0.5},
        {true, true, 0.0, 0.0, kLightestLead},  {true, false, 0.3, 0.0, kLightestLead},
        {true, false, 0.0, 0.0, kLightestLead}, {false, true, 0.0, 0.0, 1.0},
        {false, true, 0.0, 0.03, 1.0},    {false, true, 0.0, 0.07, 1.0},
        {false, true, 0.0, 0.12, 1.0},    {false, false, 0.3, 0.0, 1.0},
        {false, false, 0.3, 0.03, 1.0},   {false, false, 0.3, 0.07, 1.0},
        {false, false, 0.3, 0.12, 1.0},   {false, false, 0.0, 0.0, 1.0},
        {false, false, 0.0, 0.07, 1.0}};
  };

  /// Paths the drill makes itself: settles, the way back (field for field paths.hpp's PathTiming).
  struct Paths {
    /// [s] a settle's least time, and the lead-in of each path run backwards.
    double settle_min{1.0};
    /// [m, rad] a base this near a posture's stays put: a small move disturbs more than it gains.
    double base_kept{0.03};
    /// [rad/s] a settle's slow joint speed.
    double joint_speed{0.5};
    /// [m/s] a settle's slow speed of base_x and base_y.
    double base_speed{0.2};
    /// A settle runs at 1/speed_share of those speeds: a Cartesian phase can leave a joint far off.
    double speed_share{3.0};
  };

  /// Looks at a hole's mark after the base moved.
  struct Looks {
    /// [s] a marker last seen longer ago gets a look with the base standing: the gyro's bias walks.
    double marker_stale{15.0};
    /// [m] room around a marker for the odometry's drift when the camera is turned onto it.
    double marker_drift{0.05};
    /// [N] the force a placement's look is checked with: none is drilled (the planner's least).
    double look_force{1.0};
    /// Looks in order: on the mark, further out, then centred between hole and marker, then
    /// at the marker from any side.
    std::vector<LookAttempt> attempts{
        {false, 0.0, 0.0}, {false, 0.1, 0.0}, {false, 0.2, 0.0}, {true, 0.2, 0.0}, {true, 0.3, 0.0}, {false, 0.85, 0.8}};
  };

  /// An area's base placement (placement.hpp).
  struct Placement {
    /// From a drawn posture a hole counts as reached by the arm alone with hole.attempts[0..this].
    std::size_t last_hole_attempt{2};
    /// Lead a placement is checked at again when the full thrust's leaves every hole out of reach.
    double light_lead{0.5};
    /// [m] the placement's look at the marker, beyond the distance that frames it, in turn.
    std::vector<double> look_further{0.0, 0.1, 0.2};
    /// Whole-body postures drawn for a placement, in turn.
    std::vector<PlacementDraw> draws =
        std::vector<PlacementDraw>(std::begin(kPlacementDraws), std::end(kPlacementDraws));
  };

  /// Whether each of an area's holes can be drilled, asked before anything moves for them
  /// (ReachSurvey, placement.hpp): whole-body postures, the base anywhere, from the full thrust
  /// to the most lenient; a hole none of them finds is not attempted.
  struct Survey {
    /// In order; a hole is reachable at the first that finds a posture.
    std::vector<HoleAttempt> attempts{{true, false, 0.0, 0.0, 1.0},
                                      {true, false, 0.0, 0.0, 0.35},
                                      {false, false, 0.0, 0.07, 1.0}};
    /// Each attempt asked up to this many times (the planner's search is randomised).
    int tries{2};
  };

  /// Blob holes: predicted blobs matched to seen ones across the odometry's drift.
  struct Blobs {
    /// [m] a predicted blob lies this near a seen one (also: a start view's blob near the surface).
    double match{0.02};
    /// [m] while the body moves, a blob is followed from frame to frame at most this far.
    double track_window{0.02};
    /// [m] two or more blobs seen together name each other up to this shift.
    double set_shift{0.15};
    /// [m] room for drift around a blob and its nearest neighbour when a look frames both.
    double set_look_drift{0.1};
    /// [m] a hole measured again from its posture is looked for this far from its prediction.
    double reanchor_distance{0.06};
  };

  /// Where the arm waits (for the planner's answer, between a hole's attempts). Holding a
  /// posture loads the arm's drives; safety stops when a drive's RMS torque over the thermal
  /// window passes its continuous torque x (1 + its effort margin). Before a request is sent
  /// to the planner, an arm whose drives are near that (measured: Inputs::heat) first goes to
  /// its homing posture and waits there until they have cooled.
  struct Rest {
    /// An arm joint's RMS torque over the thermal window above this fraction of its continuous
    /// torque, or the load it holds now above `hold` of it: the arm rests first.
    double above{0.85};
    double hold{1.0};
    /// Rested until every arm joint's RMS is below this fraction of its continuous torque.
    double until{0.7};
    /// [s] of robot time rested at most; the request then goes as it is.
    double timeout{20.0};
  };

  /// While drilling, the thrust folds back as the hottest arm drive's RMS torque over the
  /// thermal window (measured: Inputs::heat) rises from `fold_start` to `fold_end` of its
  /// continuous torque (safety stops at 1 + its effort margin, 1.1); at `fold_end` the feed
  /// stops, the bit at rest in the hole, until the drive cooled below `fold_start`.
  struct Thermal {
    double fold_start{0.95};
    double fold_end{1.05};
  };

  Camera camera;
  Buffers buffers;
  Liveness liveness;
  PlanRequests plan_requests;
  Approach approach;
  Bim bim;
  Hole hole;
  Paths paths;
  Looks looks;
  Placement placement;
  Survey survey;
  Blobs blobs;
  Rest rest;
  Thermal thermal;
  DrillParams motion;  ///< the drilling of one hole (drill_motion.hpp)
};

/// Reads Params from the YAML file `file` (sections as Params' members, every key optional).
/// Unknown keys, bad values and broken rules across keys throw DrillError naming the file, the
/// key and the line: "drill.yaml: hole.attempts[3].further: expected a number >= 0, got 'x'
/// (line 14)".
Params load_params(const std::filesystem::path& file);
/// The same from YAML text; `source` names it in errors.
Params parse_params(const std::string& yaml, const std::string& source);
/// Reads `doc` over the defaults and checks the rules across keys (throws config::ConfigError);
/// a test reads the shipped file with it to compare the file with the defaults.
Params read_params(config::Document& doc);

}  // namespace concert::drill
