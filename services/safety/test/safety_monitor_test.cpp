// Unit tests of the safety core: latching, reset rules, liveliness, limits, params.
#include "safety/safety_monitor.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

namespace concert::safety {
namespace {

using namespace std::chrono_literals;

const TimePoint kT0{std::chrono::seconds(1000)};

bool contains(const std::vector<std::string>& causes, const std::string& text) {
  for (const auto& c : causes) {
    if (c.find(text) != std::string::npos) return true;
  }
  return false;
}

/// Default parameters but for the liveliness bound. The tests call check_liveliness only where
/// it matters, standing for a monitor that checks every period: no stall detection.
Params with_liveliness_timeout(std::chrono::milliseconds timeout) {
  Params p;
  p.liveliness_timeout = timeout;
  p.stall_checks = 0;
  return p;
}

TEST(SafetyMonitor, StartsRunningWithNothingWatched) {
  SafetyMonitor m(Params{}, kT0);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  EXPECT_FALSE(m.status().reset_required);
  m.check_liveliness(kT0 + 1h);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  EXPECT_TRUE(m.watched().empty());
}

TEST(SafetyMonitor, EveryEStopInputStopsAndNamesItself) {
  for (std::size_t i = 0; i < kEStopSourceCount; ++i) {
    const auto source = static_cast<EStopSource>(i);
    SafetyMonitor m(Params{}, kT0);
    m.set_estop(source, true, "test");
    EXPECT_EQ(m.status().mode, Mode::kStopped) << to_string(source);
    EXPECT_TRUE(m.status().reset_required);
    ASSERT_EQ(m.status().causes.size(), 1u);
    EXPECT_EQ(m.status().causes[0], "estop: " + std::string(to_string(source)) + " engaged (test)");
  }
}

TEST(SafetyMonitor, StopIsLatchedAfterRelease) {
  SafetyMonitor m(Params{}, kT0);
  m.set_estop(EStopSource::kWireless, true, "");
  m.set_estop(EStopSource::kWireless, false, "");
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_TRUE(m.status().reset_required);
  EXPECT_EQ(m.status().causes, std::vector<std::string>{"estop: wireless engaged"});
  EXPECT_TRUE(m.engaged_inputs().empty());
}

// The state says which inputs are engaged (a display shows those, not the inputs' own samples),
// and a release alone is a new state to publish.
TEST(SafetyMonitor, StatusNamesTheEngagedInputsAndAReleaseIsANewRevision) {
  SafetyMonitor m(Params{}, kT0);
  EXPECT_TRUE(m.status().engaged.empty());
  m.set_estop(EStopSource::kSoftware, true, "gui");
  m.set_estop(EStopSource::kWireless, true, "");
  EXPECT_EQ(m.status().engaged, (std::vector<EStopSource>{EStopSource::kWireless, EStopSource::kSoftware}));
  const auto before = m.revision();
  m.set_estop(EStopSource::kSoftware, false, "tool");
  EXPECT_GT(m.revision(), before);
  EXPECT_EQ(m.status().engaged, std::vector<EStopSource>{EStopSource::kWireless});
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  const auto released = m.revision();
  m.set_estop(EStopSource::kSoftware, false, "tool");  // re-sent: nothing new
  EXPECT_EQ(m.revision(), released);

  SafetyMonitor restarted(Params{}, kT0);
  restarted.restore(m.latched(), kT0);
  EXPECT_EQ(restarted.status().engaged, std::vector<EStopSource>{EStopSource::kWireless});
}

TEST(SafetyMonitor, ResetRefusedWhileAnyInputEngaged) {
  SafetyMonitor m(Params{}, kT0);
  m.set_estop(EStopSource::kButtonFrontLeft, true, "");
  m.set_estop(EStopSource::kButtonRearRight, true, "");
  m.set_estop(EStopSource::kButtonFrontLeft, false, "");
  const auto r = m.reset("operator", kT0);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.message.find("still engaged: button rear right"), std::string::npos) << r.message;
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_EQ(m.status().causes.size(), 2u);

  m.set_estop(EStopSource::kButtonRearRight, false, "");
  const auto ok = m.reset("operator", kT0);
  EXPECT_TRUE(ok.accepted) << ok.message;
  EXPECT_NE(ok.message.find("2 cause(s) cleared"), std::string::npos) << ok.message;
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  EXPECT_FALSE(m.status().reset_required);
  EXPECT_TRUE(m.status().causes.empty());
}

TEST(SafetyMonitor, ReleaseAloneNeverRestarts) {
  SafetyMonitor m(Params{}, kT0);
  m.set_estop(EStopSource::kSoftware, true, "");
  for (int i = 0; i < 10; ++i) {
    m.set_estop(EStopSource::kSoftware, false, "");
    m.check_liveliness(kT0 + std::chrono::seconds(i));
  }
  EXPECT_EQ(m.status().mode, Mode::kStopped);
}

TEST(SafetyMonitor, ReEngagingAfterResetStopsAgainAndRevisionMoves) {
  SafetyMonitor m(Params{}, kT0);
  const auto r0 = m.revision();
  m.set_estop(EStopSource::kSoftware, true, "a");
  const auto r1 = m.revision();
  EXPECT_GT(r1, r0);
  m.set_estop(EStopSource::kSoftware, true, "a");  // re-sent: nothing new
  EXPECT_EQ(m.revision(), r1);
  m.set_estop(EStopSource::kSoftware, false, "");
  ASSERT_TRUE(m.reset("op", kT0).accepted);
  EXPECT_GT(m.revision(), r1);
  m.set_estop(EStopSource::kSoftware, true, "b");
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_EQ(m.status().causes, std::vector<std::string>{"estop: software engaged (b)"});
}

TEST(SafetyMonitor, ResetWhileRunningIsHarmless) {
  SafetyMonitor m(Params{}, kT0);
  const auto r = m.reset("op", kT0);
  EXPECT_TRUE(r.accepted);
  EXPECT_NE(r.message.find("nothing to reset"), std::string::npos);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
}

TEST(SafetyMonitor, SilentTaskServiceStopsNamingIt) {
  SafetyMonitor m(with_liveliness_timeout(500ms), kT0);
  m.on_heartbeat("planner", "manip", false, kT0);
  m.on_heartbeat("robot", "rt", false, kT0);
  for (int i = 1; i <= 10; ++i) {  // robot keeps beating, planner goes silent after 0 ms
    m.on_heartbeat("robot", "rt", false, kT0 + i * 100ms);
    m.check_liveliness(kT0 + i * 100ms);
    if (i <= 5) {
      EXPECT_EQ(m.status().mode, Mode::kRunning) << i;
    }
  }
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  ASSERT_EQ(m.status().causes.size(), 1u);
  EXPECT_EQ(m.status().causes[0], "liveliness: planner@manip silent for 0.60 s (bound 0.50 s)");
  EXPECT_EQ(m.watched(), (std::vector<std::pair<std::string, bool>>{{"planner@manip", true},
                                                                    {"robot@rt", false}}));
}

TEST(SafetyMonitor, ItsOwnStallIsNobodysSilence) {
  // The safety process starved for 1.7 s (a loaded machine: CI saw drill, planner and robot
  // "silent for 1.69 s" at once): the heartbeats waiting in its readers are no silence.
  SafetyMonitor m(Params{}, kT0);  // 1 s bound, checks every 50 ms, a stall past 5 of them
  m.on_heartbeat("planner", "manip", false, kT0);
  m.on_heartbeat("robot", "rt", false, kT0);
  m.check_liveliness(kT0 + 50ms);
  m.check_liveliness(kT0 + 1750ms);  // the monitor ran 1.7 s late
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  EXPECT_EQ(m.own_stalls(), 1u);
  // The robot beats on; the planner really is gone: caught one bound of checked time after
  // its last heartbeat.
  for (int i = 1; i <= 40; ++i) {
    m.on_heartbeat("robot", "rt", false, kT0 + 1750ms + i * 50ms);
    m.check_liveliness(kT0 + 1750ms + i * 50ms);
    if (i <= 18) {
      EXPECT_EQ(m.status().mode, Mode::kRunning) << i;
    }
  }
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  ASSERT_EQ(m.status().causes.size(), 1u);
  EXPECT_NE(m.status().causes[0].find("planner@manip silent"), std::string::npos);
  EXPECT_EQ(m.own_stalls(), 1u);
}

TEST(SafetyMonitor, UnwatchedServicesAreIgnored) {
  SafetyMonitor m(with_liveliness_timeout(100ms), kT0);
  m.on_heartbeat("modelgen", "rt", false, kT0);
  m.on_heartbeat("discovery", "rt", false, kT0);
  m.check_liveliness(kT0 + 10s);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
}

TEST(SafetyMonitor, CleanStopOfATaskIsNotAFaultButOfTheRobotIs) {
  SafetyMonitor m(with_liveliness_timeout(100ms), kT0);
  m.on_heartbeat("drill", "manip", false, kT0);
  m.on_heartbeat("drill", "manip", true, kT0 + 50ms);
  m.check_liveliness(kT0 + 10s);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  m.on_heartbeat("robot", "rt", false, kT0);
  m.on_heartbeat("robot", "rt", true, kT0 + 50ms);
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_TRUE(contains(m.status().causes, "robot@rt stopped")) << m.status().causes[0];
}

TEST(SafetyMonitor, SilentRobotBlocksResetSilentTaskIsForgottenByReset) {
  SafetyMonitor m(with_liveliness_timeout(100ms), kT0);
  m.on_heartbeat("robot", "rt", false, kT0);
  m.on_heartbeat("nav", "navpc", false, kT0);
  m.check_liveliness(kT0 + 200ms);
  EXPECT_EQ(m.status().causes.size(), 2u);
  auto r = m.reset("op", kT0 + 200ms);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.message.find("robot service robot@rt is silent"), std::string::npos) << r.message;

  m.on_heartbeat("robot", "rt", false, kT0 + 250ms);  // robot back, nav still gone
  r = m.reset("op", kT0 + 260ms);
  EXPECT_TRUE(r.accepted) << r.message;
  EXPECT_NE(r.message.find("no longer watching silent nav@navpc"), std::string::npos) << r.message;
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  m.check_liveliness(kT0 + 300ms);
  EXPECT_EQ(m.status().mode, Mode::kRunning);  // nav forgotten, robot fresh

  m.on_heartbeat("nav", "navpc", false, kT0 + 310ms);  // nav returns: watched again
  m.on_heartbeat("robot", "rt", false, kT0 + 500ms);
  m.check_liveliness(kT0 + 500ms);
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_TRUE(contains(m.status().causes, "liveliness: nav@navpc silent"));
}

TEST(SafetyMonitor, AServiceRestartedWithinTheBoundStopsNamingIt) {
  // A killed planner that `concert up` restarts within the liveliness bound is never silent
  // long enough: a heartbeat from another process names the restart.
  SafetyMonitor m(with_liveliness_timeout(1000ms), kT0);
  m.on_heartbeat("planner", "manip", false, kT0, "process-1");
  m.on_heartbeat("planner", "manip", false, kT0 + 200ms, "process-1");
  m.on_heartbeat("robot", "rt", false, kT0 + 200ms, "robot-1");
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  m.on_heartbeat("planner", "manip", false, kT0 + 700ms, "process-2");
  m.check_liveliness(kT0 + 800ms);
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  ASSERT_EQ(m.status().causes.size(), 1u);
  EXPECT_EQ(m.status().causes[0],
            "liveliness: planner@manip restarted (its process died without stopping; a new one "
            "took its place)");
  // The new process is watched; a reset lets the robot go again.
  m.on_heartbeat("robot", "rt", false, kT0 + 900ms, "robot-1");
  EXPECT_TRUE(m.reset("op", kT0 + 900ms).accepted);
  m.on_heartbeat("planner", "manip", false, kT0 + 1000ms, "process-2");
  m.check_liveliness(kT0 + 1100ms);
  EXPECT_EQ(m.status().mode, Mode::kRunning);

  // Already stopped for its silence: the restart adds no second cause.
  m.on_heartbeat("robot", "rt", false, kT0 + 2500ms, "robot-1");
  m.check_liveliness(kT0 + 2500ms);
  ASSERT_EQ(m.status().causes.size(), 1u);
  EXPECT_TRUE(contains(m.status().causes, "planner@manip silent"));
  m.on_heartbeat("planner", "manip", false, kT0 + 2600ms, "process-3");
  EXPECT_EQ(m.status().causes.size(), 1u);

  // A clean stop, then a new process: no fault. Unknown processes ("") are never a restart.
  SafetyMonitor clean(with_liveliness_timeout(1000ms), kT0);
  clean.on_heartbeat("drill", "manip", false, kT0, "a");
  clean.on_heartbeat("drill", "manip", true, kT0 + 100ms, "a");
  clean.on_heartbeat("drill", "manip", false, kT0 + 300ms, "b");
  clean.on_heartbeat("nav", "nav", false, kT0, "");
  clean.on_heartbeat("nav", "nav", false, kT0 + 100ms, "c");
  EXPECT_EQ(clean.status().mode, Mode::kRunning);
}

TEST(SafetyMonitor, ARestoredMonitorKeepsTheStopTheInputsAndTheWatchedServices) {
  SafetyMonitor before(with_liveliness_timeout(1000ms), kT0);
  before.on_heartbeat("robot", "rt", false, kT0, "robot-1");
  before.on_heartbeat("planner", "manip", false, kT0, "planner-1");
  before.on_heartbeat("drill", "manip", false, kT0, "drill-1");
  before.set_estop(EStopSource::kWireless, true, "operator");
  const uint64_t revision = before.latched_revision();
  before.on_heartbeat("planner", "manip", false, kT0 + 100ms, "planner-1");  // a beat: no change
  EXPECT_EQ(before.latched_revision(), revision);
  const LatchedState state = before.latched();
  EXPECT_EQ(state.mode, Mode::kStopped);
  EXPECT_EQ(state.engaged, std::vector<EStopSource>{EStopSource::kWireless});
  EXPECT_EQ(state.watched.size(), 3u);
  EXPECT_EQ(state.watched.at("planner@manip"), "planner-1");

  // Through the file format and back.
  const LatchedState read = parse_latched_state(to_yaml(state), "state.yaml");
  EXPECT_EQ(read, state) << to_yaml(state);

  const TimePoint t1 = kT0 + 60s;  // the restarted safety service
  SafetyMonitor after(with_liveliness_timeout(1000ms), t1);
  after.restore(read, t1);
  EXPECT_EQ(after.status().mode, Mode::kStopped);
  EXPECT_EQ(after.status().causes, before.status().causes);
  EXPECT_EQ(after.latched(), state);
  // The input is still engaged: no reset.
  EXPECT_FALSE(after.reset("op", t1).accepted);
  after.set_estop(EStopSource::kWireless, false, "");
  // The same robot and planner processes beat on; the drill came back as a new process while
  // the safety service was down: a restart; nav was never watched.
  after.on_heartbeat("robot", "rt", false, t1 + 200ms, "robot-1");
  after.on_heartbeat("planner", "manip", false, t1 + 200ms, "planner-1");
  after.on_heartbeat("drill", "manip", false, t1 + 200ms, "drill-2");
  EXPECT_TRUE(contains(after.status().causes, "drill@manip restarted"));
  EXPECT_FALSE(contains(after.status().causes, "planner@manip"));
  EXPECT_TRUE(after.reset("op", t1 + 300ms).accepted);
  EXPECT_EQ(after.status().mode, Mode::kRunning);
  // A watched service that never beats again after the restore is silent the bound after the
  // first status heard (the restarted service's readers took 1.5 s to match here).
  SafetyMonitor gone(with_liveliness_timeout(1000ms), t1);
  gone.restore(read, t1);
  gone.set_estop(EStopSource::kWireless, false, "");
  gone.check_liveliness(t1 + 1500ms);
  EXPECT_FALSE(contains(gone.status().causes, "silent"));
  gone.on_heartbeat("safety", "rt", false, t1 + 1500ms, "self");  // its own status: not the wire
  gone.on_heartbeat("robot", "rt", false, t1 + 1500ms, "robot-1");
  gone.on_heartbeat("drill", "manip", false, t1 + 1600ms, "drill-1");
  gone.check_liveliness(t1 + 2400ms);
  EXPECT_FALSE(contains(gone.status().causes, "silent"));
  gone.on_heartbeat("robot", "rt", false, t1 + 2500ms, "robot-1");
  gone.on_heartbeat("drill", "manip", false, t1 + 2500ms, "drill-1");
  gone.check_liveliness(t1 + 2600ms);
  EXPECT_TRUE(contains(gone.status().causes, "planner@manip silent"));
  EXPECT_FALSE(contains(gone.status().causes, "drill@manip"));
  // Every watched service died while the safety service was down: silent all the same.
  SafetyMonitor all_gone(with_liveliness_timeout(1000ms), t1);
  all_gone.restore(read, t1);
  all_gone.check_liveliness(t1 + 4900ms);
  EXPECT_EQ(all_gone.status().causes.size(), 1u);  // the wireless input only
  all_gone.check_liveliness(t1 + 5000ms);
  all_gone.check_liveliness(t1 + 5100ms);
  EXPECT_TRUE(contains(all_gone.status().causes, "robot@rt silent"));
  EXPECT_TRUE(contains(all_gone.status().causes, "planner@manip silent"));
}

TEST(LatchedState, RunningEmptyAndErrorsNamingFileAndKey) {
  const LatchedState empty;
  EXPECT_EQ(parse_latched_state(to_yaml(empty), "s.yaml"), empty);
  auto error_of = [](const std::string& yaml) {
    try {
      (void)parse_latched_state(yaml, "s.yaml");
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error_of("mode: HALTED"),
            "s.yaml: mode: expected one of RUNNING, STOPPED, got 'HALTED' (line 1)");
  EXPECT_EQ(error_of("mode: STOPPED\ncauses: [a]\ncause_keys: []\n"),
            "s.yaml: cause_keys: expected one per cause (1 causes, 0 keys) (line 3)");
  EXPECT_EQ(error_of("mode: STOPPED\n"), "s.yaml: causes: a stop needs its causes");
  EXPECT_EQ(error_of("engaged: [nowhere]"), "s.yaml: engaged: unknown e-stop input 'nowhere' (line 1)");
  EXPECT_EQ(error_of("mode: RUNNING\nwatched: {a@b: \"\xe6\x31\"}\n"), "s.yaml: not valid UTF-8 (byte 30)");
  EXPECT_EQ(error_of("engaged: [wireless]"),
            "s.yaml: engaged: RUNNING with an e-stop input engaged (line 1)");
  EXPECT_EQ(error_of("watched: {planner: x}"), "s.yaml: watched: 'planner' is not service@host (line 1)");
  EXPECT_NE(error_of("bogus: 1").find("s.yaml: bogus: unknown key"), std::string::npos);

  // Written through a temporary file and a rename.
  const std::string file = std::filesystem::temp_directory_path() /
                           ("safety_state_" + std::to_string(::getpid()) + ".yaml");
  LatchedState s;
  s.mode = Mode::kStopped;
  s.causes = {"liveliness: planner@manip silent for 1.04 s (bound 1.00 s)"};
  s.cause_keys = {"silent:planner@manip"};
  s.watched = {{"robot@rt", "01.0f.aa"}};
  save_latched_state(file, s);
  EXPECT_EQ(load_latched_state(file), s);
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));
  std::filesystem::remove(file);
  EXPECT_THROW(save_latched_state("/nonexistent/dir/state.yaml", s), std::runtime_error);
}

TEST(SafetyMonitor, RequiredRobotMustBeHeardAfterStart) {
  Params p = with_liveliness_timeout(1s);
  p.require_robot = true;
  SafetyMonitor m(p, kT0);
  m.check_liveliness(kT0 + 900ms);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  m.check_liveliness(kT0 + 1100ms);
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_EQ(m.status().causes[0], "liveliness: robot not heard within 1.00 s of the start");
  EXPECT_FALSE(m.reset("op", kT0 + 1200ms).accepted);
  m.on_heartbeat("robot", "rt", false, kT0 + 1300ms);
  EXPECT_TRUE(m.reset("op", kT0 + 1300ms).accepted);
}

// J1_A: 100 N m peak, 60 N m continuous torque.
model::LimitsTable two_joints() {
  return model::LimitsTable({{"J1_A", "A", -2.0, 2.0, 1.5, 100.0, 60.0}, {"J2_A", "A", -1.0, 1.0, 2.0, 50.0, 50.0}}, "test");
}

JointSample sample(uint32_t version, double q1, double qd1, double tau1) {
  return {version, {"J1_A", "J2_A"}, {q1, 0.0}, {qd1, 0.0}, {tau1, 0.0}};
}

TEST(SafetyMonitor, LimitsWithinBoundsAndTolerancesAreFine) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(3, two_joints());
  EXPECT_EQ(m.on_joint_state(sample(3, 2.015, 1.6, 109.0), kT0), SampleOutcome::kChecked);
  EXPECT_EQ(m.on_joint_state(sample(3, -2.015, -1.6, -109.0), kT0), SampleOutcome::kChecked);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
}

TEST(SafetyMonitor, PositionVelocityEffortViolationsStop) {
  const std::pair<JointSample, std::string> violations[] = {
      {sample(3, 2.1, 0.0, 0.0),
       "limits: joint J1_A position 2.100 beyond [-2.000, 2.000] (model v3)"},
      {sample(3, 0.0, -1.7, 0.0), "limits: joint J1_A velocity -1.700 beyond +-1.650 (model v3)"},
      {sample(3, 0.0, 0.0, 111.0),
       "limits: joint J1_A effort 111.00 beyond the peak torque +-110.00 (model v3)"},
      {sample(3, std::nan(""), 0.0, 0.0),
       "limits: joint J1_A position nan beyond [-2.000, 2.000] (model v3)"},
  };
  for (const auto& [s, cause] : violations) {
    SafetyMonitor m(Params{}, kT0);
    m.set_model(3, two_joints());
    m.on_joint_state(s, kT0);
    ASSERT_EQ(m.status().mode, Mode::kStopped) << cause;
    EXPECT_EQ(m.status().causes[0], cause);
  }
}

// The limits rule (libs/model): the demo's drilling approach loads J2_E (Large A actuator,
// 460 N m peak, 160 N m continuous) with transients of ~177 N m; that is no stop. A torque
// beyond the peak, or a load above the continuous torque held for the thermal window, stops.
model::LimitsTable elbow() { return model::LimitsTable({{"J2_E", "E", -2.75, 2.75, 2.14, 460.0, 160.0}}, "test"); }

JointSample elbow_sample(double tau) { return {1, {"J2_E"}, {0.5}, {0.2}, {tau}}; }

TEST(SafetyLimitsRule, TransientAboveContinuousButBelowPeakIsNoStop) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, elbow());
  // 1 s at 100 Hz of -176.82 N m (the demo's transient), then back to 120 N m for 30 s.
  auto t = kT0;
  for (int i = 0; i < 100; ++i, t += 10ms) m.on_joint_state(elbow_sample(-176.82), t);
  for (int i = 0; i < 3000; ++i, t += 10ms) m.on_joint_state(elbow_sample(120.0), t);
  EXPECT_EQ(m.status().mode, Mode::kRunning) << m.status().causes.front();
}

TEST(SafetyLimitsRule, BeyondPeakStopsAtOnce) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, elbow());
  m.on_joint_state(elbow_sample(-510.0), kT0);
  ASSERT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_EQ(m.status().causes[0], "limits: joint J2_E effort -510.00 beyond the peak torque +-506.00 (model v1)");
}

TEST(SafetyLimitsRule, SustainedAboveContinuousStops) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, elbow());
  // 220 N m (below the peak, above 160 x 1.1 = 176 N m) held: the RMS over the 5 s window
  // passes 176 N m after 5 s x ln(1 / (1 - (176/220)^2)) = 5.1 s.
  auto t = kT0;
  int samples = 0;
  for (; samples < 2000 && m.status().mode == Mode::kRunning; ++samples, t += 10ms) m.on_joint_state(elbow_sample(220.0), t);
  ASSERT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_GT(samples, 450);
  EXPECT_LT(samples, 560);
  EXPECT_EQ(m.status().causes[0].rfind("limits: joint J2_E RMS effort 176.", 0), 0u) << m.status().causes[0];
  EXPECT_NE(m.status().causes[0].find("over the 5.0 s thermal window beyond the continuous torque 176.00 (model v1)"),
            std::string::npos)
      << m.status().causes[0];
}

JointSample stamped_elbow_sample(double tau, int64_t stamp_ns) {
  JointSample s = elbow_sample(tau);
  s.stamp_ns = stamp_ns;
  return s;
}

// The robot publishes at 100 Hz; its drive holds the RMS near the continuous torque (150 N m)
// with a transient of 400 N m (below the 460 N m peak) now and then. This process stalls for
// 1.5 s before each transient: the samples of the stall queue up and arrive together, the
// transient first. Weighed by arrival, the transient counted for the whole stall (RMS 241 N m,
// a stop of a robot whose drive is within its rating); weighed by the robot's stamps it counts
// for its 10 ms.
TEST(SafetyLimitsRule, SamplesCountForTheRobotsClockNotForTheirArrival) {
  const auto run = [](bool stamped) {
    SafetyMonitor m(Params{}, kT0);
    m.set_model(1, elbow());
    auto arrival = kT0;
    int64_t stamp = 1'000'000'000;
    for (int burst = 0; burst < 10 && m.status().mode == Mode::kRunning; ++burst) {
      for (int i = 0; i < 500; ++i, arrival += 10ms, stamp += 10'000'000) {
        m.on_joint_state(stamped_elbow_sample(150.0, stamped ? stamp : 0), arrival);
      }
      arrival += 1500ms;  // the stall: 150 samples queued, delivered at once
      for (int i = 0; i < 150; ++i, stamp += 10'000'000) {
        m.on_joint_state(stamped_elbow_sample(i == 0 ? 400.0 : 150.0, stamped ? stamp : 0), arrival);
      }
    }
    return m.status();
  };
  const SafetyStatus by_stamp = run(true);
  EXPECT_EQ(by_stamp.mode, Mode::kRunning) << by_stamp.causes.front();
  // Unstamped samples can only be weighed by arrival: the same load then stops, as it did.
  const SafetyStatus by_arrival = run(false);
  ASSERT_EQ(by_arrival.mode, Mode::kStopped);
  EXPECT_EQ(by_arrival.causes[0].rfind("limits: joint J2_E RMS effort", 0), 0u) << by_arrival.causes[0];
}

// The sustained bound still holds by the stamps, and a robot whose clock starts again (a
// restarted robot service) neither stops nor forgets the load.
TEST(SafetyLimitsRule, StampedSustainedLoadStopsAcrossARestartedClock) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, elbow());
  auto arrival = kT0;
  int64_t stamp = 5'000'000'000;
  int samples = 0;
  for (; samples < 300; ++samples, arrival += 10ms, stamp += 10'000'000) {
    m.on_joint_state(stamped_elbow_sample(220.0, stamp), arrival);
  }
  ASSERT_EQ(m.status().mode, Mode::kRunning);
  stamp = 10'000'000;  // the robot restarted: its clock begins again
  for (; samples < 2000 && m.status().mode == Mode::kRunning; ++samples, arrival += 10ms, stamp += 10'000'000) {
    m.on_joint_state(stamped_elbow_sample(220.0, stamp), arrival);
  }
  ASSERT_EQ(m.status().mode, Mode::kStopped);
  // 5.1 s of 220 N m from cold (SustainedAboveContinuousStops), one sample lost at the restart.
  EXPECT_GT(samples, 450);
  EXPECT_LT(samples, 560);
}

TEST(SafetyLimitsRule, ANewModelStartsCold) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, elbow());
  auto t = kT0;
  for (int i = 0; i < 400; ++i, t += 10ms) m.on_joint_state(elbow_sample(220.0), t);
  m.set_model(1, elbow());
  for (int i = 0; i < 400; ++i, t += 10ms) m.on_joint_state(elbow_sample(220.0), t);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
}

TEST(SafetyMonitor, RepeatedViolationGivesOneCause) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(3, two_joints());
  for (int i = 0; i < 1000; ++i) m.on_joint_state(sample(3, 2.5, 0.0, 0.0), kT0);
  EXPECT_EQ(m.status().causes.size(), 1u);
}

TEST(SafetyMonitor, OtherModelVersionsAndNoModelAreNotChecked) {
  SafetyMonitor m(Params{}, kT0);
  EXPECT_EQ(m.on_joint_state(sample(3, 9.0, 0.0, 0.0), kT0), SampleOutcome::kNoModel);
  m.set_model(4, two_joints());
  EXPECT_EQ(m.on_joint_state(sample(3, 9.0, 0.0, 0.0), kT0), SampleOutcome::kOtherModelVersion);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
  EXPECT_EQ(m.on_joint_state(sample(4, 9.0, 0.0, 0.0), kT0), SampleOutcome::kChecked);
  EXPECT_EQ(m.status().mode, Mode::kStopped);
}

TEST(SafetyMonitor, InfiniteLimitsOfContinuousJointsNeverTrip) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, model::LimitsTable({{"wheel", "A", -1e300, 1e300, 20.0, 50.0, 40.0}}, "test"));
  m.on_joint_state({1, {"wheel"}, {1e6}, {19.0}, {10.0}}, kT0);
  EXPECT_EQ(m.status().mode, Mode::kRunning);
}

TEST(SafetyMonitor, MalformedJointStateStops) {
  SafetyMonitor m(Params{}, kT0);
  m.set_model(1, two_joints());
  m.on_joint_state({1, {"J1_A", "J2_A"}, {0.0}, {}, {}}, kT0);
  EXPECT_EQ(m.status().mode, Mode::kStopped);
  EXPECT_EQ(m.status().causes[0],
            "limits: malformed joint state: 2 names, 1 positions, 0 velocities, 0 efforts");
}

TEST(SafetyMonitor, RandomSamplesTripExactlyWhenOutsideBounds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> q(-2.5, 2.5), qd(-2.0, 2.0), tau(-130.0, 130.0);
  int tripped = 0;
  for (int i = 0; i < 2000; ++i) {
    SafetyMonitor m(Params{}, kT0);
    m.set_model(1, two_joints());
    const auto s = sample(1, q(rng), qd(rng), tau(rng));
    m.on_joint_state(s, kT0);
    const bool outside = std::abs(s.position[0]) > 2.02 || std::abs(s.velocity[0]) > 1.65 ||
                         std::abs(s.effort[0]) > 110.0;
    EXPECT_EQ(m.status().mode == Mode::kStopped, outside) << i;
    tripped += outside ? 1 : 0;
  }
  EXPECT_GT(tripped, 100);
  EXPECT_LT(tripped, 1900);
}

TEST(SafetyParams, DefaultsAndOverrides) {
  const auto d = parse_params("", "empty");
  EXPECT_EQ(d.liveliness_timeout, 1000ms);
  const auto p = parse_params(
      "liveliness_timeout: 0.5\nrobot_service: rob\ntask_services: [a, b]\nrequire_robot: true\n"
      "position_tolerance: 0.1\nvelocity_margin: 0.2\neffort_margin: 0.3\npublish_period: "
      "0.1\ncheck_period: 0.02\nstall_checks: 0\nnice: 5\n",
      "x");
  EXPECT_EQ(p.liveliness_timeout, 500ms);
  EXPECT_EQ(p.robot_service, "rob");
  EXPECT_EQ(p.task_services, (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(p.require_robot);
  EXPECT_DOUBLE_EQ(p.position_tolerance, 0.1);
  EXPECT_DOUBLE_EQ(p.velocity_margin, 0.2);
  EXPECT_DOUBLE_EQ(p.effort_margin, 0.3);
  EXPECT_EQ(p.publish_period, 100ms);
  EXPECT_EQ(p.check_period, 20ms);
  EXPECT_EQ(p.stall_checks, 0);
  EXPECT_EQ(p.nice, 5);
  EXPECT_EQ(d.nice, -10);
  EXPECT_THROW(parse_params("nice: -21\n", "x"), std::runtime_error);
}

TEST(SafetyParams, ShippedConfigListsEveryParameterWithItsDefault) {
  auto doc = config::Document::load(std::string(CONCERT_SOURCE_DIR) +
                                    "/services/safety/config/safety.yaml");
  (void)read_params(doc);
  EXPECT_EQ(doc.keys().size(), 11u);
  EXPECT_TRUE(doc.differences_from_defaults().empty())
      << ::testing::PrintToString(doc.differences_from_defaults());
}

void expect_error(const std::string& yaml, const std::string& text) {
  try {
    parse_params(yaml, "f.yaml");
    ADD_FAILURE() << "no error for: " << yaml;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST(SafetyParams, ErrorsNameFileKeyAndLine) {
  expect_error("[1, 2]", "f.yaml: expected a map of parameters, got a list");
  expect_error("liveliness: 1",
               "f.yaml: liveliness: unknown key (line 1); known keys: check_period, "
               "effort_margin, liveliness_timeout,");
  expect_error("liveliness_timeout: fast",
               "f.yaml: liveliness_timeout: expected a duration in seconds in (0, 3600], got "
               "'fast' (line 1)");
  expect_error("liveliness_timeout: -1", "f.yaml: liveliness_timeout: expected a duration");
  expect_error("task_services: planner", "f.yaml: task_services: expected a list of strings");
  expect_error("task_services: [a, [b]]",
               "f.yaml: task_services: item 1: expected a non-empty string, got a list");
  expect_error("require_robot: maybe",
               "f.yaml: require_robot: expected true or false, got 'maybe'");
  expect_error("effort_margin: -0.1",
               "f.yaml: effort_margin: expected a number >= 0, got '-0.1' (line 1)");
  expect_error("liveliness_timeout: 0.1\ncheck_period: 0.5",
               "f.yaml: check_period: must not exceed liveliness_timeout (line 2)");
  expect_error("a: [", "f.yaml: not valid YAML");
  try {
    load_params("/nonexistent/safety.yaml");
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "parameters file '/nonexistent/safety.yaml' cannot be opened");
  }
}

}  // namespace
}  // namespace concert::safety
