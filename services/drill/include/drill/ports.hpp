#pragma once
// What the drilling mission's behaviour tree asks of the rest of the robot. Every call returns
// at once: long work (navigation, planning, a trajectory, a hole) is started by one call and
// polled on later ticks. The DDS adapter implements it with the other services' topics; the
// tests implement it with fakes. Plain C++, no DDS.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "drill/mission.hpp"

namespace concert::drill {

/// State of a started operation.
enum class Progress { kRunning, kSucceeded, kFailed };

/// A polled operation's state and, when it failed, why ("no blob visible in area 'a2'").
struct Outcome {
  Progress progress{Progress::kRunning};
  std::string reason;
  static Outcome running() { return {}; }
  static Outcome succeeded() { return {Progress::kSucceeded, {}}; }
  static Outcome failed(std::string why) { return {Progress::kFailed, std::move(why)}; }
};

/// Base pose in the map frame: x, y [m], theta [rad].
struct BasePose {
  double x{0.0};
  double y{0.0};
  double theta{0.0};
};

/// A drilling area once located: its frame (world/map frame, origin on the wall surface, z
/// along the outward normal, x horizontal to the right seen from the front, y up) and, for
/// a BIM wall area, where the base stands to reach it.
struct ResolvedArea {
  Eigen::Isometry3d frame{Eigen::Isometry3d::Identity()};
  std::optional<BasePose> base;
};

/// One hole to drill: its frame on the wall (origin where the hole starts, z along the outward
/// normal) and how it was found.
struct DrillPoint {
  Eigen::Isometry3d frame{Eigen::Isometry3d::Identity()};
  std::string label;   ///< "blob 1", "aruco 7 hole 3"
  bool servo{false};   ///< visual servoing on the blob while drilling (blobs), else kinematics alone
  int marker{-1};      ///< ArUco holes: the marker's id (-1 for a blob)
  int pattern_index{-1};  ///< ArUco holes: the hole's index in the marker's pattern
};

/// Whether the mounted robot can drill a hole, as the planner judged it before anything moved
/// for it (ReachSurvey, drill/placement.hpp).
enum class Reach {
  kUnknown,      ///< not asked, or the planner could not say (refused, another model)
  kReachable,    ///< a whole-body posture was found; `why` says at which thrust
  kUnreachable,  ///< no posture at any thrust; `why` is the planner's reason
};
struct HoleReach {
  Reach reach{Reach::kUnknown};
  std::string why;
};
const char* to_string(Reach r);

/// The robot as the mission's tree sees it.
class MissionPorts {
 public:
  virtual ~MissionPorts() = default;

  /// Whether the robot may move: succeeded when safety is RUNNING and every service the
  /// mission uses is alive; failed with the reason otherwise (e-stop, a lost service);
  /// kRunning while a service the mission uses has not been heard yet, shortly after the
  /// mission began (the tree then waits; the port bounds how long).
  virtual Outcome health() = 0;

  /// Locates an area (a BIM wall: frame + base pose; a point or a pixel: the normal from the
  /// point cloud). May stay kRunning while it waits for sensor data.
  virtual void resolve(std::size_t area, const AreaSpec& spec) = 0;
  virtual Outcome resolution(std::size_t area, ResolvedArea& out) = 0;

  /// Drives the base to a pose (autonomous navigation), the arm first taken to its homing
  /// posture (the transport posture navigation drives with).
  virtual void navigate(const BasePose& goal) = 0;
  virtual Outcome navigation() = 0;

  /// Plans the whole-body approach to an area frame (camera at the working distance along
  /// the normal). `after` is the area whose approach posture the plan starts from (the arm
  /// retracts there after drilling), or none to start from the robot's current state. Several
  /// areas may be planned while another executes.
  virtual void plan(std::size_t area, const Eigen::Isometry3d& frame, std::optional<std::size_t> after) = 0;
  virtual Outcome planning(std::size_t area) = 0;

  /// Executes a planned approach (the robot must stand where the plan started).
  virtual void execute(std::size_t area) = 0;
  virtual Outcome execution() = 0;

  /// Detects the area's drilling points in the drill camera's images (blobs, or the ArUco
  /// marker and its pattern).
  virtual void detect(std::size_t area, const AreaSpec& spec, const ResolvedArea& located) = 0;
  virtual Outcome detection(std::vector<DrillPoint>& points) = 0;

  /// Asks, before anything moves for them, whether the robot can drill each of the area's holes
  /// still to drill (ReachSurvey): `reach` gets one verdict per hole of `holes`, in order. A hole
  /// judged unreachable is not attempted; the report says why.
  virtual void classify(std::size_t area, const std::vector<DrillPoint>& holes) = 0;
  virtual Outcome classification(std::vector<HoleReach>& reach) = 0;

  /// Places the base for the area's holes still to drill (drill/placement.hpp): the whole body
  /// moves once, to where the arm alone reaches them all and the camera the area's mark, or the
  /// base stays where the approach put it (then each hole's own posture may move it). Failed
  /// with the reason when a motion it started failed (the area fails, the robot is stopped).
  /// Succeeded, `order` says in which order to drill the holes (indices into `holes`): those the
  /// arm alone reaches from where the base ends first, so that a hole that moves the base does
  /// not carry the odometry's drift into the others. Left empty: in the order given.
  virtual void place(std::size_t area, const std::vector<DrillPoint>& holes) = 0;
  virtual Outcome placement(std::vector<std::size_t>& order) = 0;

  /// Moves the bit in front of a point, along its normal (Cartesian impedance).
  virtual void align(const DrillPoint& point) = 0;
  virtual Outcome alignment() = 0;

  /// Drills the point to `depth` [m] (eq. 3; visual servoing if point.servo).
  virtual void drill(const DrillPoint& point, double depth) = 0;
  virtual Outcome drilling() = 0;

  /// Pulls the bit out and returns the arm to the area's approach posture.
  virtual void retract() = 0;
  virtual Outcome retraction() = 0;

  /// Takes the arm to its homing posture, the base standing: the mission's last step, so the
  /// robot ends ready to drive (navigation refuses an arm out of its transport posture) or to
  /// have its tool swapped.
  virtual void stow() = 0;
  virtual Outcome stowing() = 0;

  /// Stops every motion at once (aborting): cancels navigation, holds the arm where it is.
  virtual void stop() = 0;
};

}  // namespace concert::drill
