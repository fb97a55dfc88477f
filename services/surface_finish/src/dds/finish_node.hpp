#pragma once
// DDS adapter of the surface finishing service: the robot model in (the arm's spraying or sanding
// tool; the areas computed on a worker thread, status READY at the version once they are, or
// "cannot finish: ..."), joint states, the lidars' planar scan (the wall and its normal) and the
// robot's trajectory statuses in; commands in; the areas (latched) and every run's status and
// report out. A spray run is executed as one joint trajectory through the robot service; the
// deposition model is fed the TCP of every measured joint state. A sand run (SandSequence) is
// a joint trajectory to the approach pose, then Cartesian impedance commands at the control
// rate with the robot service's admittance along the TCP's z; the robot's wrench estimate
// (concert/robot/ee_wrench) gives the statistics and the stops, the safety state stops it.
//
// DDS callbacks only queue; one control thread does the rest.
#include <atomic>
#include <chrono>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <tuple>

#include "concert/common/command_once.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "surface_finish/areas.hpp"
#include "surface_finish/deposition.hpp"
#include "surface_finish/sand_sequence.hpp"
#include "surface_finish/serpentine.hpp"
#include "surface_finish/wall_fit.hpp"

namespace concert::surface_finish::dds {

struct NodeParams {
  double rate{50.0};                             ///< control rate [Hz]
  AreaParams areas;
  PathParams path;
  ToolSpec spray{Task::kSpray, 0.3, 0.1, 0.1};   ///< 0.3 m standoff, 0.1 m coats (paper 6.2)
  ToolSpec sand{Task::kSand, 0.0, 0.23, 0.1};    ///< disc diameter: an estimate
  double sand_force{
      30.0};  ///< [N] the sanding areas keep the torques for this force (the largest taken)
  /// Sanding path: 0.1 m/s strokes, no settling hold, the approach from 5 cm at 5 cm/s (as the
  /// offline run, SandRunParams::path).
  PathParams sand_path{0.1, 0.5, 0.02, 0.05, 0.05, 0.0, 0.0, 0.8};
  SandParams sanding;          ///< the sequence (its force is the request's)
  /// A sand run stops when no force estimate came for this long [s], counted over this node's
  /// ticks (each at most 0.1 s: a stall of this process is not the robot's silence).
  double wrench_timeout{2.0};
  double distance_tolerance{0.15};  ///< measured wall distance vs the working distance [m]
  double scan_max_age{2.0};         ///< [s]
  std::string out_dir;              ///< where each run's report JSON and PNG go ("" = nowhere)
};

class FinishNode {
 public:
  FinishNode(concert::dds::Participant& participant, NodeParams params, std::ostream& log);
  ~FinishNode();
  FinishNode(const FinishNode&) = delete;
  FinishNode& operator=(const FinishNode&) = delete;
  /// Runs the control loop until `stop` is set (a running path is stopped, the arm held).
  void spin(const std::atomic<bool>& stop);

 private:
  struct Prepared {
    std::shared_ptr<const model::RobotModel> model;
    std::shared_ptr<Reach> reach;
    std::optional<AreaMap> areas;
    Task task{Task::kSpray};
    std::string error;
  };
  struct Measured {
    std::int64_t stamp_ns{0};
    std::vector<std::string> names;
    std::vector<double> positions;
  };
  struct Run {
    std::uint32_t request_id{0};
    std::uint32_t trajectory_id{0};
    SerpentinePlan plan;
    WallFrame wall;
    std::unique_ptr<SprayDeposition> deposition;
    std::size_t index{0};          // plan sample the measured posture is at
    std::int64_t last_stamp{0};
    // Measured postures followed, those at a plan sample with the tool on, and those the valve
    // let paint (the report says so when the coverage is low).
    std::size_t postures{0}, tool_on{0}, painted{0};
    double progress{0.0};
    double wall_distance{0.0};
    std::chrono::steady_clock::time_point sent{};
    std::unique_ptr<SandSequence> sand;  // a sand run (no deposition)
    std::shared_ptr<Reach> reach;        // the tool of the model the run was planned on
    std::chrono::steady_clock::time_point last_tick{}, last_status{};
    double silence{0.0};  // [s] without a force estimate (see NodeParams::wrench_timeout)
  };
  struct Wrench {
    std::int64_t stamp_ns{0};
    Eigen::Vector3d force{0.0, 0.0, 0.0};
  };

  void tick();
  void on_model(const msg::RobotModel& m);
  void finish_preparation();
  void handle(const msg::FinishCommand& c);
  void start_spray(const msg::FinishCommand& c);
  void start_sand(const msg::FinishCommand& c);
  void follow_sand();
  void send_sand(const SandCommand& command);
  void send_trajectory(Run& run, std::size_t last_sample);
  /// Ends the run: `leave_wall` (a user's abort), a sanding tool in contact leaves the wall
  /// first (SandSequence::abort) and the run ends when it has; else it stops where it is.
  void abort_run(const std::string& why, bool leave_wall = false);
  void follow_run();
  void end_run(msg::FinishState state, const std::string& reason);
  void publish(std::uint32_t request_id, msg::FinishState state, const std::string& reason, const Run* run,
               const std::string& report = {});
  void refuse(const msg::FinishCommand& c, const std::string& why);
  [[nodiscard]] Eigen::VectorXd q_of(const Measured& m) const;
  /// The measured joints in `model`'s kinematics order (a joint it lacks is left out).
  [[nodiscard]] static Eigen::VectorXd q_in(const model::RobotModel& model, const Measured& m);
  [[nodiscard]] WallFit measure_wall();
  /// measure_wall(), refused (FinishError) unless the wall is where `areas` were computed for.
  [[nodiscard]] WallFit measure_wall_for(const AreaMap& areas);
  /// The arm's joints from the latest joint state (the caller checked there is one).
  [[nodiscard]] Eigen::VectorXd q_now_measured();
  /// A run of command `c` planned for `tool` (the area or its rect, the wall measured now, the
  /// serpentine from the arm's current joints); `target` gets "<rect> of area '<id>'" and
  /// `inliers` the wall fit's point count, for the log. Spray and sand share it.
  [[nodiscard]] Run plan_run(const msg::FinishCommand& c, const ToolSpec& tool, PathParams path,
                             std::string& target, int& inliers);
  void hold_here();
  void log_line(const std::string& line);

  NodeParams params_;
  std::ostream& log_;
  concert::dds::StatusReporter status_;
  concert::dds::Writer<msg::FinishAreas> areas_writer_;
  concert::dds::Writer<msg::FinishStatus> status_writer_;
  concert::dds::Writer<msg::JointTrajectoryCommand> trajectories_;
  concert::dds::Writer<msg::CartesianImpedanceCommand> cartesian_;

  std::mutex mutex_;  // the inbox below
  std::optional<msg::RobotModel> new_model_;
  std::deque<msg::FinishCommand> commands_;
  std::deque<Measured> measured_;  // joint states since the last tick (bounded)
  std::optional<Measured> latest_;
  std::optional<msg::LaserScan> scan_;
  std::chrono::steady_clock::time_point scan_seen_{};
  std::map<std::uint32_t, msg::TrajectoryStatus> trajectory_statuses_;
  std::deque<Wrench> wrenches_;  // force estimates since the last tick, while a run is on (bounded)
  std::optional<msg::SafetyState> safety_;

  std::uint64_t version_seen_{0};
  std::future<Prepared> preparing_;
  std::uint64_t preparing_version_{0};
  Prepared current_;
  std::uint64_t current_version_{0};
  /// The version the robot's commands carry: current_version_, or a new model's at once when a
  /// run in contact leaves the wall under it (leave_for_new_model) before its areas are computed.
  std::uint64_t command_version_{0};
  concert::CommandOnce taken_;  // (request id, stamp) of the commands taken (a resent one is ignored)
  std::optional<Run> run_;
  std::atomic<bool> run_active_{false};  // joint states are queued only while a run is on
  std::uint32_t next_trajectory_{0x46000001};

  // Readers last: their callbacks use everything above.
  concert::dds::Reader<msg::RobotModel> model_reader_;
  concert::dds::Reader<msg::JointState> joint_reader_;
  concert::dds::Reader<msg::LaserScan> scan_reader_;
  concert::dds::Reader<msg::FinishCommand> command_reader_;
  concert::dds::Reader<msg::TrajectoryStatus> trajectory_reader_;
  concert::dds::Reader<msg::EndEffectorWrench> wrench_reader_;
  concert::dds::Reader<msg::SafetyState> safety_reader_;
};

}  // namespace concert::surface_finish::dds
