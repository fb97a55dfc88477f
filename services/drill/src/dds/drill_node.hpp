#pragma once
// DDS adapter of the drill service: the robot model in (the drill and its camera, status READY
// at the version or "cannot drill: ..."); joint states, odometry, the drill camera's frames,
// the safety state, the planner's, robot's and nav's answers and the other services' statuses
// into drill::Inputs; missions and aborts to the engine (drill/engine.hpp), which decides. As
// the engine's DrillSink it writes nav goals, planner requests, joint trajectories, holds and
// Cartesian impedance commands, and the mission's status and report.
//
// DDS callbacks only queue or fill Inputs; one control thread ticks the engine.

#include <atomic>
#include <deque>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>

#include "concert/dds/endpoint.hpp"
#include "concert/dds/status_reporter.hpp"
#include "concert/mobile_base/map_frame.hpp"
#include "dds/conversions.hpp"
#include "drill/engine.hpp"
#include "drill/inputs.hpp"
#include "drill/params.hpp"

namespace concert::drill::dds {

/// What the service is started with.
struct NodeParams {
  std::string patterns;         ///< default hole-pattern table (a mission may name its own)
  double rate{50.0};            ///< control rate [Hz]
  /// Where each camera view in which a looked-for mark was not found is written (PNG, the mark's
  /// expected pixel crossed); empty: nowhere.
  std::string unseen_frames_dir;
  Params tuning;  ///< config/drill.yaml (drill/params.hpp)
};

class DrillNode final : private DrillSink {
 public:
  DrillNode(concert::dds::Participant& participant, NodeParams params, std::ostream& log);
  ~DrillNode() override;
  DrillNode(const DrillNode&) = delete;
  DrillNode& operator=(const DrillNode&) = delete;

  /// Runs the control loop until `stop` is set (then stops any motion).
  void spin(const std::atomic<bool>& stop);

 private:
  struct Inbox {
    std::optional<msg::RobotModel> model;
    std::deque<msg::DrillMission> missions;
    std::deque<msg::DrillAbort> aborts;
  };

  // DrillSink: the engine's commands and reports onto the topics.
  void plan(const PlanAsk& ask) override;
  void trajectory(std::uint32_t id, std::uint32_t model_version, const std::vector<std::string>& names,
                  const std::vector<PathSample>& samples) override;
  void navigate(std::uint32_t id, std::uint32_t model_version, const BasePose& goal) override;
  void cancel_navigation() override;
  void hold(std::uint32_t model_version, const JointPositions& arm) override;
  void cartesian(std::uint32_t model_version, const std::string& frame, const CartesianReference& r) override;
  void mission_status(std::uint32_t mission_id, const MissionStatus& status, const MissionReport& report) override;
  void refused(const std::string& why) override;
  void log(const std::string& line) override;

  void tick(double now);
  void apply_model(const msg::RobotModel& m);
  void on_image(const msg::Image& image, bool depth);
  void on_info(const msg::CameraInfo& info);
  void assemble_frame();  // with mutex_ held

  NodeParams params_;
  std::ostream& log_;
  std::mutex log_mutex_;
  mutable std::mutex mutex_;  // inbox, the camera's messages and its name below
  Inbox inbox_;
  Inputs inputs_;  // what was measured and heard (thread-safe)
  // Where the odometry frame lies in the map (nav's localisation). Thread-safe on its own.
  mobile_base::MapFrame map_frame_;
  std::optional<msg::Image> rgb_, depth_;
  std::optional<msg::CameraInfo> info_;
  std::string camera_;                      // sensor name of the drill camera (for the callbacks)
  std::atomic<bool> camera_wanted_{false};  // a mission runs: the camera callbacks keep frames

  concert::dds::StatusReporter status_;
  concert::dds::Writer<msg::DrillStatus> status_out_;
  concert::dds::Writer<msg::NavGoal> nav_goals_;
  concert::dds::Writer<msg::NavCancel> nav_cancels_;
  concert::dds::Writer<msg::PlanRequest> plan_requests_;
  concert::dds::Writer<msg::JointTrajectoryCommand> trajectories_;
  concert::dds::Writer<msg::CartesianImpedanceCommand> cartesian_;
  concert::dds::Writer<msg::JointCommand> joint_commands_;
  DrillEngine engine_;  // control thread only; before the readers, whose callbacks outlive none of it
  concert::dds::Reader<msg::RobotModel> models_;
  concert::dds::Reader<msg::JointState> joints_in_;
  concert::dds::Reader<msg::Odometry> odometry_in_;
  concert::dds::Reader<msg::SafetyState> safety_in_;
  concert::dds::Reader<msg::ServiceStatus> services_in_;
  concert::dds::Reader<msg::PlanResult> plans_in_;
  concert::dds::Reader<msg::TrajectoryStatus> trajectories_in_;
  concert::dds::Reader<msg::NavStatus> nav_in_;
  concert::dds::Reader<msg::NavLocalisation> localisation_in_;
  concert::dds::Reader<msg::Image> rgb_in_;
  concert::dds::Reader<msg::Image> depth_in_;
  concert::dds::Reader<msg::CameraInfo> info_in_;
  concert::dds::Reader<msg::DrillMission> missions_in_;
  concert::dds::Reader<msg::DrillAbort> aborts_in_;
};

}  // namespace concert::drill::dds
