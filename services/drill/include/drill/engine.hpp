#pragma once
// The drill's mission engine: the mission tree's ports (drill/ports.hpp) over plain inputs and
// outputs. It takes what was measured and heard from Inputs and the map frame, decides (each
// hole's posture, looks at its mark, re-measures, alignment, drilling, retreat, the base's
// placement, replans and resends) and says what to send through a DrillSink. The DDS adapter
// feeds Inputs and implements the sink with the topics; tests use fakes. Plain C++, no DDS.
// One control thread calls everything here.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <chrono>
#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "concert/common/command_once.hpp"
#include "concert/mobile_base/map_frame.hpp"
#include "concert/model/robot_model.hpp"
#include "drill/area_detection.hpp"
#include "drill/drill_motion.hpp"
#include "drill/drill_rig.hpp"
#include "drill/inputs.hpp"
#include "drill/mission_tree.hpp"
#include "drill/odometry_drift.hpp"
#include "drill/params.hpp"
#include "drill/paths.hpp"
#include "drill/patterns.hpp"
#include "drill/perception.hpp"
#include "drill/placement.hpp"
#include "drill/plan_exchange.hpp"
#include "drill/ports.hpp"

namespace concert::drill {

/// A mission as the drill service takes it (concert/drill/mission).
struct MissionOrder {
  std::uint32_t mission_id{0};
  std::int64_t stamp_ns{0};  ///< with the id: a mission written again is taken once
  std::string name;
  std::string yaml;      ///< the mission file's text
  std::string base_dir;  ///< where the mission's relative paths start
  bool resume{false};    ///< skip what the last run of this mission's name finished
};

/// An abort (concert/drill/abort): of `mission_id`, or of whatever runs when 0.
struct AbortOrder {
  std::uint32_t mission_id{0};
  std::string source;
  std::string reason;
};

/// Where the engine's commands and reports go. Each call returns at once.
class DrillSink {
 public:
  virtual ~DrillSink() = default;
  /// A request to the whole-body planner (sent again, same id, while unacknowledged).
  virtual void plan(const PlanAsk& ask) = 0;
  /// A joint-space path for the robot to track (base joints first, as the planner names them).
  virtual void trajectory(std::uint32_t id, std::uint32_t model_version, const std::vector<std::string>& names,
                          const std::vector<PathSample>& samples) = 0;
  /// A navigation goal for the base (map frame), and its cancel.
  virtual void navigate(std::uint32_t id, std::uint32_t model_version, const BasePose& goal) = 0;
  virtual void cancel_navigation() = 0;
  /// The arm held where it is (position mode); the base stops.
  virtual void hold(std::uint32_t model_version, const JointPositions& arm) = 0;
  /// A Cartesian impedance reference for the drill's TCP frame `frame`.
  virtual void cartesian(std::uint32_t model_version, const std::string& frame, const CartesianReference& r) = 0;
  /// The mission's status and report.
  virtual void mission_status(std::uint32_t mission_id, const MissionStatus& status, const MissionReport& report) = 0;
  /// A mission refused, why (the service's refusals count it).
  virtual void refused(const std::string& why) = 0;
  /// A line for the service's log.
  virtual void log(const std::string& line) = 0;
};

/// What the engine is started with.
struct EngineParams {
  std::string patterns;           ///< default hole-pattern table (a mission may name its own)
  std::string unseen_frames_dir;  ///< where views in which a looked-for mark was not found go (PNG); empty: nowhere
  Params tuning;                  ///< config/drill.yaml
};

class DrillEngine final : public MissionPorts {
 public:
  DrillEngine(EngineParams params, Inputs& inputs, mobile_base::MapFrame& map_frame, DrillSink& sink);
  ~DrillEngine() override;
  DrillEngine(const DrillEngine&) = delete;
  DrillEngine& operator=(const DrillEngine&) = delete;

  /// A new robot model (older versions are ignored): the rig it offers (null: it cannot drill,
  /// `why` says why), a running mission aborted. Returns the service's status message.
  std::string apply_model(std::uint32_t version, std::shared_ptr<const DrillRig> rig, const std::string& why);
  /// Takes a mission, or refuses it (reported through the sink).
  void start_mission(const MissionOrder& m);
  /// Aborts the running mission (when `a` names it or names none).
  void abort(const AbortOrder& a);
  /// One control period at `now` [s, monotonic]: resends, the motion, the tree, the status.
  void tick(double now);
  /// The motion's part of a control period at `now` [s, monotonic], alone: the resends, then
  /// the motion's state machine (what tick() runs before the tree while a mission is active).
  /// For tests that call the ports (align, drill, retract, place) as the mission tree would.
  void step_motion(double now);
  /// A mission was accepted and has not ended.
  [[nodiscard]] bool mission_active() const;
  /// A stopped mission's bit is being pulled back out of the wall (no new mission until it is).
  [[nodiscard]] bool leaving_wall() const { return motion_ == Motion::kLeave; }
  /// The newest model version taken (0: none).
  [[nodiscard]] std::uint64_t model_version() const { return model_version_; }
  /// The service stops: a running mission is aborted and its status sent.
  void shutdown();

  // MissionPorts (control thread).
  Outcome health() override;
  void resolve(std::size_t area, const AreaSpec& spec) override;
  Outcome resolution(std::size_t area, ResolvedArea& out) override;
  void navigate(const BasePose& goal) override;
  Outcome navigation() override;
  void plan(std::size_t area, const Eigen::Isometry3d& frame,
            std::optional<std::size_t> after) override;
  Outcome planning(std::size_t area) override;
  void execute(std::size_t area) override;
  Outcome execution() override;
  void detect(std::size_t area, const AreaSpec& spec, const ResolvedArea& located) override;
  Outcome detection(std::vector<DrillPoint>& points) override;
  void classify(std::size_t area, const std::vector<DrillPoint>& holes) override;
  Outcome classification(std::vector<HoleReach>& reach) override;
  void place(std::size_t area, const std::vector<DrillPoint>& holes) override;
  Outcome placement(std::vector<std::size_t>& order) override;
  void align(const DrillPoint& point) override;
  Outcome alignment() override;
  void drill(const DrillPoint& point, double depth) override;
  Outcome drilling() override;
  void retract() override;
  Outcome retraction() override;
  void stow() override;
  Outcome stowing() override;
  void stop() override;

  /// A joint state with its odometry, as received (robot clock).
  using Sample = JointSample;

 private:
  struct Plan {
    std::uint32_t request_id{0};
    PlanAsk request;  ///< as sent (a retry sends it again under a new id)
    int attempts{1};
    std::optional<PlanReply> result;
    std::vector<std::string> names;  ///< of the trajectory
    Eigen::VectorXd end;             ///< last sample's positions
  };
  enum class Motion {
    kNone,
    kApproachHole,
    kLookAtHole,
    kLookReanchor,
    kReanchor,
    kAlign,
    kDrill,
    kRetractOut,
    kSettle,
    kBackToPosture,
    kCheckLook,   // a marker hole's whole-body posture planned, not executed: is a look possible from it?
    kBodyToHole,  // that posture's path sent to the robot by the drill itself
    kCheckedLook,  // then the look's path check_look() planned, sent likewise
    kBackForLook,  // the marker not seen from a look: back onto the posture for the next look
    kBackThenReplan,  // back from a look onto the posture, then the posture planned again there
    kLeave,  // a stopped mission's bit pulled back out of the wall along the hole's axis, then held
    // An area's base placement (place()): the arm alone asked for every hole (and the camera
    // for the mark) from where the base stands or from a drawn posture; a whole-body posture
    // drawn; the move there; the camera onto the mark; the mark measured again.
    kPlaceCheck,
    kPlaceDraw,
    kPlaceMove,
    kPlaceLook,
    kPlaceSee,
    kPlaceLookAgain  // the marker not seen: the camera further out, the arm alone (executed)
  };

  // The survey of an area's holes (classify(), ReachSurvey): one planned-only whole-body
  // request out per hole undecided (its id, 0: none).
  struct Survey {
    std::vector<DrillPoint> holes;
    std::optional<ReachSurvey> survey;
    std::vector<std::uint32_t> ids;
    double started{0.0};  // now_ [s]
    bool logged{false};
  } survey_;
  void survey_ask(std::size_t i);
  bool stow_returning_{false};  // stow(): back along the holes' paths before the homing

  // An area's base placement (place(), drill/placement.hpp): its holes, the tally, the
  // requests out, the postures drawn and each one's look.
  using PlannedPath = Path;
  struct Placement {
    std::vector<DrillPoint> holes;
    double started{0.0};  // now_ [s]
    std::optional<PlacementChoice> choice;
    // The arm alone onto each hole (planned only): the request out and which of
    // Params::hole.attempts' first three (0, 3 and 7 cm further out) it asks.
    struct Check {
      std::uint32_t id{0};
      std::size_t attempt{0};
      PlanAsk request;
    };
    std::vector<Check> hole_checks;
    Check look_check;  // the camera onto the mark (id 0: none asked), attempt of Params::placement.look_further
    std::uint32_t draw{0};                   // the whole body's posture drawn
    std::vector<std::vector<std::string>> names;                 // per draw
    std::vector<std::vector<PathSample>> bodies;      // per draw (empty: none found)
    std::vector<std::vector<PathSample>> looks;       // per draw (empty: no look)
    std::vector<double> look_distances;  // per draw: the camera's distance of its look [m]
    std::vector<bool> standing_reached;  // per hole: the arm alone reaches it from where the base stands
    std::vector<std::vector<bool>> reached;  // per draw, per hole: from the posture drawn
    std::vector<std::size_t> order;      // the holes' order to drill (reached first)
    std::vector<bool> placed;            // per hole: reached by the arm alone where the base ends
    double lead{1.0};                    // the thrust checked: a lead of Params::hole.attempts'
    std::size_t looks_again{0};          // of Params::placement.look_further: the look from where the base stands
    double look_distance{0.0};           // its camera distance [m]
    std::uint32_t look_again{0};         // its request
    PlannedPath again_path;
  } placement_;
  [[nodiscard]] PlanAsk placement_request(const Eigen::Isometry3d& goal);
  void place_check(bool drawn);
  void place_next();
  void control_placement();
  // control_placement's steps, one per placement state.
  void place_check_step();
  void place_draw_step();
  void place_move_step();
  void place_look_step();
  void place_look_again_step();
  void place_see_step();
  [[nodiscard]] std::optional<PlanReply> answered(std::uint32_t id) const;
  [[nodiscard]] std::size_t chosen_draw() const;
  void resend(Placement::Check& c);
  void place_look(std::size_t attempt);
  [[nodiscard]] std::string placement_time() const;
  // A placement's end: an area's (the mission tree's place() port) succeeded, or a hole's
  // (place_for_hole) goes on to the hole's alignment; `stood`: the base stays where it stands.
  void placement_done(bool stood);
  void place_for_hole();
  void publish_status(bool force);
  void control_motion();
  // control_motion's steps, one per Motion state, and the Cartesian phases.
  void hole_posture_step();
  void no_posture_after_remeasure(const PlanReply& r);
  void next_hole_attempt(const PlanReply& r);
  void check_look_step();
  void body_to_hole_step();
  void checked_look_step();
  void look_at_hole_step();
  void look_reanchor_step();
  void back_then_replan_step();
  void reanchor_step();
  void back_for_look_step();
  void settle_step();
  void cartesian_step();
  void send_cartesian(const CartesianReference& r);
  void send_hold();
  // Leaving contact, the first thing a stop does at a hole (abort, a health failure, a new
  // model with the same arm): the bit aligned onto, in or leaving the wall is pulled back along
  // the hole's axis to the standoff, then the arm holds. False when the bit is clear already.
  bool start_leave();
  void leave_step();
  void start_align(const Sample& s);
  // The hole's motion runs on the robot's clock, the stamp of the joint sample whose tip it
  // follows: a loaded machine slows the simulated robot, and a reference ramped or a timeout
  // counted on the wall clock would then run ahead of the arm and fail holes the arm drills.
  static double robot_time(const Sample& s) { return 1e-9 * static_cast<double>(s.stamp_ns); }
  /// The mission's hole depth [m] (Params::hole.default_depth before a mission).
  [[nodiscard]] double hole_depth() const;
  void start_reanchor(Motion next);
  void look_at_hole(std::size_t first = 0);
  bool prepare_look();
  PlanAsk look_plan(std::size_t attempt) const;
  void check_look(std::size_t attempt);
  void posture_reached();
  void hole_request_write(bool may_rest = false);
  /// Moves the area's blob holes by `shift` (world frame): odometry drifted by that much.
  void shift_area(const Eigen::Vector3d& shift);
  /// While the whole body moves to a blob hole's posture: the area's blobs followed in the
  /// newest camera frame (shift_area), odometry's drift taken out as it grows.
  void track_area();
  /// Plans the hole's drilling posture again at point_, the arm alone: the bit's tip on the
  /// hole's axis, `further` [m] beyond the hole's distance, its reach checked if `reach`, the
  /// thrust of `lead` (light_drilling) checked.
  void replan_hole(bool reach, double further, double lead);
  void request_hole_posture();
  /// Plans the hole's whole-body posture again at point_ (the hole measured again), with the
  /// request that reached the first one: when no arm-alone posture reaches it from there.
  void replan_body();
  void replan_after_look();
  [[nodiscard]] double camera_fov() const;
  /// A hole measured again with the camera turned onto its blob / marker (kLookReanchor).
  bool remeasure_looked_blob(const CameraView& camera);
  bool remeasure_looked_marker(const CameraView& camera);
  /// The view in which point_'s mark, expected at `mark` (world), was not found, written to
  /// EngineParams::unseen_frames_dir when one is set.
  void keep_unseen_view(const CameraView& camera, const Eigen::Vector3d& mark);
  int unseen_views_{0};
  /// From the look posture back onto the whole body's posture, then the alignment.
  void back_to_posture(const Sample& s, Motion next = Motion::kBackToPosture);
  // Straight from `here` onto `p`'s last posture, at rest there (drill::settle_path); the base
  // kept where it stands when within Params::paths.base_kept of the posture's, said in the log.
  std::vector<PathSample> settle_path(const PlannedPath& p, const PathSample& here);
  void request_look(std::size_t attempt);
  std::uint32_t send_trajectory(const std::vector<std::string>& names, const std::vector<PathSample>& samples);
  void log_line(const std::string& line);

  EngineParams params_;
  const Params& tuning_ = params_.tuning;
  Inputs& inputs_;
  // Where the odometry frame lies in the map (nav's localisation): a BIM wall area is in the map,
  // the camera and the planner's requests in the odometry frame. Thread-safe on its own.
  mobile_base::MapFrame& map_frame_;
  DrillSink& sink_;
  std::chrono::steady_clock::time_point mission_started_{};  // health waits a while from here
  std::shared_ptr<const DrillRig> rig_;

  // Control thread.
  std::string rig_error_;
  std::uint64_t model_version_{0};
  std::unique_ptr<MissionTree> tree_;
  std::unique_ptr<Mission> mission_;
  std::uint32_t mission_id_{0};
  // `concert drill run` writes a mission again
  // every second until a status names it, and each is taken once.
  concert::CommandOnce missions_seen_;                 // (mission id, stamp) of the missions taken
  std::map<std::string, MissionReport> last_reports_;  // by mission name, for resume
  std::optional<PatternTable> patterns_;
  std::chrono::steady_clock::time_point last_status_{};
  std::string last_active_;
  // Request ids (plan, trajectory, navigation) start anywhere: a restarted drill numbering from 1
  // again would take the planner's latched results of its predecessor's requests for its own.
  std::uint32_t next_request_{(std::random_device{}() & 0x3fffffffu) + 1u};
  struct Unacknowledged {
    PlanAsk request;
    double sent{0.0};  // last sent (now_) [s]
    int resends{0};
  };
  std::map<std::uint32_t, Unacknowledged> unacknowledged_;  // plan requests by id
  // A plan request goes to the planner at once, or, when the arm's drives run hot
  // (Params::Rest), after the arm has gone home and cooled: the planner answers it from there.
  // `may_rest`: the engine assumes nothing of where the arm waits for the answer (a hole's
  // first posture request, its next attempt); the others expect the arm where it is.
  void send_plan(const PlanAsk& r, bool may_rest = false);
  void forward_plan(const PlanAsk& r);
  PlanAsk home_ask();
  // Why the arm must rest before `r` is planned ("J3_E: RMS 151 N m over the thermal window,
  // 0.94 of continuous"), or "" when it may wait where it is.
  [[nodiscard]] std::string rest_reason(const PlanAsk& r) const;
  // Each arm joint's heat (Inputs::heat) with its continuous torque [N m].
  struct ArmHeat {
    std::string joint;
    Inputs::Heat heat;
    double continuous{0.0};
  };
  [[nodiscard]] std::vector<ArmHeat> arm_heat() const;
  // The arm joints' largest RMS torque over the thermal window, as a fraction of continuous.
  [[nodiscard]] double arm_rms_share() const;
  void rest_step();
  void fold_thrust();
  void release_held(const std::string& why);
  std::vector<PlanAsk> held_requests_;  // waiting for the rest's end, in the order asked
  std::uint32_t rest_request_{0};       // the arm's homing while it rests; 0 once home
  std::uint32_t rest_return_{0};        // before it: the way back along the holes' paths (trajectory); 0 once back
  void rest_home();
  std::optional<std::uint32_t> send_way_back();
  double rest_since_{-1.0};             // robot time [s] the arm was home; < 0 before
  void resend_unacknowledged();
  std::map<std::size_t, std::future<ResolvedArea>> resolving_;
  std::map<std::size_t, std::int64_t> resolve_since_;
  std::map<std::size_t, AreaSpec> resolve_specs_;
  std::map<std::size_t, Eigen::Isometry3d> bim_frames_;  // BIM wall areas' frames in the map
  // How far odometry drifted, from the marks seen again (the planner's requests carry it as
  // odom_in_map while nav localises nothing): the areas' surfaces as first measured (map, outward
  // normal), each hole a landmark ("area:label").
  OdometryDrift drift_;
  struct Surface {
    Eigen::Vector3d point, normal;
  };
  std::map<std::size_t, Surface> surfaces_;
  // A blob area's blobs as the start view located the area showed them (odometry frame then),
  // before the approach drifted odometry: the set that names its blobs after the approach.
  std::map<std::size_t, std::vector<DrillPoint>> start_blobs_;
  /// The located area's centre moved by how the start view's blobs appear now (the approach's
  /// drift along the wall); nothing without two of them matched.
  void follow_start_blobs(const CameraView& camera, ResolvedArea& located);
  /// A hole (point_) seen again at `in_odom` after the base moved: the drift from it, logged.
  void hole_seen_again(const Eigen::Vector3d& in_odom);
  [[nodiscard]] std::string landmark(std::size_t area, const std::string& label) const;
  std::uint32_t nav_request_{0};
  // Before a navigation goal and at the mission's end: the planner's request that takes the arm
  // home (0: none running), and the goal sent once it is there.
  std::uint32_t home_request_{0};
  /// Asks the planner to take the arm home (executed), the base standing.
  void send_home();
  /// The homing's outcome: kRunning until the planner's answer, failed with its reason.
  Outcome homing();
  BasePose nav_goal_;
  std::map<std::size_t, Plan> plans_;
  std::optional<std::size_t> executing_area_;
  std::uint32_t trajectory_request_{0};
  // Detection.
  struct Detection {
    std::size_t area{0};
    AreaSpec spec;
    ResolvedArea located;
    std::int64_t since_ns{0};
    std::optional<Outcome> outcome;
    std::vector<DrillPoint> points;
  } detection_;
  // The drilling motion.
  Motion motion_{Motion::kNone};
  bool leave_paused_{false};  // a safety stop holds the robot: the leave starts again after it
  bool shutting_down_{false};  // the service stops: hold, there is no next period to leave in
  bool leave_allowed_{true};   // false while a new model with another arm stops the mission
  DrillMotion drill_motion_;
  DrillPoint point_;
  Eigen::Isometry3d base_T_world_{Eigen::Isometry3d::Identity()};  // fixed while drilling
  std::int64_t servo_since_ns_{0};
  std::uint32_t hole_plan_request_{0};
  PlanAsk hole_request_;
  double hole_distance_{0.0};  // the bit tip's distance from the wall a hole's posture asks for [m]
  double camera_to_tip_{0.0};  // the tool's camera to its tip along the camera's axis [m]
  std::size_t hole_attempt_{0};  // which of Params::hole.attempts the hole's posture request is
  double drilling_lead_{1.0};    // the lead the hole's posture holds the thrust of (light_drilling)
  std::string light_why_;        // why the hole is drilled at drilling_lead_ < 1 (the log)
  std::int64_t reanchor_since_ns_{0};
  std::vector<DrillPoint> area_points_;  // the current area's holes as detected
  PlannedPath hole_path_;          // of the hole being approached
  PlannedPath look_path_;          // of the camera turned to the hole's mark
  std::uint32_t look_request_{0};  // the plan request turning the camera to the marker
  bool looked_{false};             // the hole's mark was looked at from its posture's base
  bool look_pushed_{false};        // the look's path is the last of hole_chain_
  std::int64_t track_since_ns_{0};  // track_area(): the last frame looked at
  int tracked_frames_{0};            // frames track_area() moved the area by, this hole
  Eigen::Vector3d tracked_{Eigen::Vector3d::Zero()};  // how far it moved the area, this hole [m]
  bool hole_replanned_{false};     // the hole's posture was planned again after its re-measure
  // The whole body's posture the hole was reached with: which of Params::hole.attempts, the hole it was
  // planned for (world), and whether it was planned once more at the hole measured again.
  std::size_t body_attempt_{0};
  Eigen::Vector3d body_goal_{Eigen::Vector3d::Zero()};
  std::size_t body_replans_{0};
  std::size_t look_attempt_{0};    // which of Params::looks.attempts the look request is
  // A marker hole's whole-body posture is planned without executing it, and a look at the marker
  // planned from its end (check_look) before the base moves: without a look there the hole is
  // drilled where odometry puts it. The candidate path, the draws of it so far, the check's
  // request and which of Params::looks.attempts it is.
  PlannedPath body_candidate_;
  std::size_t body_draws_{0};
  std::uint32_t check_request_{0};
  std::size_t check_attempt_{0};
  std::size_t checked_look_{0};  // the Params::looks.attempts attempt the check found (the look starts there)
  PlannedPath checked_path_;     // its path from the candidate's end; empty: none found
  // No candidate has a look: the base is placed for the hole alone (Params::hole.place_unseen),
  // from further out, with a look at the marker, once per hole. The area's placement is kept
  // aside meanwhile (align() reads which holes it reached at which thrust).
  bool hole_placing_{false};
  std::string placed_for_;            // the hole (label) last placed for, this area
  std::optional<double> placed_lead_;  // the thrust its placement reached it at; none: not reached
  Placement area_placement_;
  bool trajectory_ran(const std::string& what);
  std::optional<PlanReply> plan_result(std::uint32_t id) const;
  void move_to_candidate();
  Eigen::Isometry3d look_goal_{Eigen::Isometry3d::Identity()};  // the mark as predicted (world)
  double look_reach_{0.0};  // how far from look_goal_ the look must see, any roll [m]; 0: the mark
                            // (a marker: its half-diagonal and Params::looks.marker_drift)
  double hole_reached_{0.0};  // camera distance of the hole's posture reached [m]
  std::map<int, Eigen::Isometry3d>
      markers_seen_;                     // marker id -> where last seen (world), this area
  std::map<int, double> markers_seen_at_;  // marker id -> when last seen (now_) [s], this area
  std::vector<PlannedPath> hole_chain_;  // the area's hole postures as reached, first to last
  bool returning_{false};                // execute(): the way back runs before the approach
  std::optional<Outcome> motion_outcome_;
  double now_{0.0};

};

}  // namespace concert::drill
