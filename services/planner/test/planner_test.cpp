// Whole-body planning on the paper's morphologies A and B and after a hot swap: every plan is
// re-checked densely (collision-free without padding, within joint, velocity, acceleration
// and torque limits, camera on the task at the end). Seeded.

#include <gtest/gtest.h>

#include <octomap/OcTree.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <vector>

#include "planner/fixtures.hpp"
#include "planner/planner.hpp"
#include "planner/trajectory.hpp"

using namespace concert::planner;

namespace {

ModelDescription morphology(char which, uint64_t version) {
  return fixtures::model_from_assembly(fixtures::data_dir() / (std::string("morphology_") + which + ".yaml"), version);
}

World site(double wall_x) {
  World w;
  w.boxes.push_back(fixtures::wall_at(wall_x));
  // A pallet on the floor to the robot's left and a pillar to its right.
  w.boxes.push_back({"pallet", Eigen::Vector3d(0.8, 0.8, 0.5), Eigen::Vector3d(1.0, 1.6, 0.25), 0.3});
  w.cylinders.push_back({"pillar", 0.15, 3.0, Eigen::Vector3d(0.9, -1.5, 1.5)});
  return w;
}

Environment environment_of(const World& w, const Params& p) {
  Environment env(p.octomap_resolution);
  env.add_world(w);
  return env;
}

// Dense re-check of one goal's plan. Returns the number of states checked.
int recheck(const PlanningModel& model, const Environment& env, const Params& params, const GoalResult& r,
            const Eigen::VectorXd& start_full, const Eigen::Isometry3d& area) {
  StateChecker exact(std::shared_ptr<const PlanningModel>(&model, [](const PlanningModel*) {}), env, params, 0.0);
  const Trajectory& t = r.trajectory;
  EXPECT_EQ(t.joint_names, model.joint_names());
  EXPECT_GE(t.points.size(), 2u);
  EXPECT_LT((t.points.front().q - model.to_planned(start_full)).norm(), 1e-9) << "trajectory does not start at the start state";
  const MotionLimits lim = motion_limits(model, params);
  int checked = 0;
  for (std::size_t i = 1; i < t.points.size(); ++i) {
    const TrajectoryPoint& a = t.points[i - 1];
    const TrajectoryPoint& b = t.points[i];
    const double dt = b.time - a.time;
    EXPECT_GT(dt, 0.0);
    EXPECT_TRUE((b.qd.cwiseAbs().array() <= lim.velocity.array() * (1 + 1e-6)).all()) << "velocity at sample " << i;
    EXPECT_TRUE((((b.qd - a.qd) / dt).cwiseAbs().array() <= lim.acceleration.array() * (1 + 1e-6)).all()) << "acceleration at " << i;
    const double span = (b.q - a.q).cwiseAbs().maxCoeff();
    const int steps = std::max(1, static_cast<int>(std::ceil(span / 0.005)));  // 5 mm / 0.005 rad
    for (int s = 1; s <= steps; ++s) {
      const Eigen::VectorXd q = a.q + (b.q - a.q) * (static_cast<double>(s) / steps);
      const Validity v = exact.check(model.to_full(q, start_full));
      EXPECT_TRUE(v.valid()) << "sample " << i << " step " << s << ": " << to_string(v.constraint) << ": " << v.detail;
      if (!v.valid()) return checked;
      checked += 1;
    }
  }
  const Eigen::VectorXd end = model.to_full(t.points.back().q, start_full);
  const Validity at_goal = exact.check(end, model.tool("").frame);
  EXPECT_TRUE(at_goal.valid()) << "goal with drilling force: " << at_goal.detail;
  const auto [pos, ang] = task_error(model, params, model.tool(""), end, area);
  EXPECT_LT(pos, 5e-3);
  EXPECT_LT(ang, 5e-3);
  EXPECT_TRUE(t.points.back().qd.isZero());
  return checked;
}

Eigen::VectorXd start_state(const PlanningModel& m) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.full_dof());
  // Arm up, slightly bent, base turned a little (the arm's parking posture).
  const auto& k = m.kinematics();
  q[2] = 0.1;
  q[k.joint_index_or_throw("J2_E")] = 0.2;
  q[k.joint_index_or_throw("J4_E")] = -0.3;
  return q;
}

// A planner with `params` on morphology `which` (model `version`) and the map of site(2.2).
std::unique_ptr<Planner> planner_at_site(const Params& params, char which, uint64_t version) {
  auto planner = std::make_unique<Planner>(params);
  planner->set_model(morphology(which, version));
  planner->set_environment(environment_of(site(2.2), params));
  return planner;
}

// `n` processes spinning on the CPU beside the test, killed and reaped when it ends; each also
// ends by itself after 10 minutes (alarm), should the test die first.
class BusyProcesses {
 public:
  explicit BusyProcesses(int n) {
    for (int i = 0; i < n; ++i) {
      const pid_t pid = ::fork();
      if (pid == 0) {
        ::alarm(600);
        volatile unsigned long spin = 0;
        for (;;) spin = spin + 1;
      }
      if (pid > 0) pids_.push_back(pid);
    }
  }
  ~BusyProcesses() {
    for (const pid_t p : pids_) {
      ::kill(p, SIGKILL);
      ::waitpid(p, nullptr, 0);
    }
  }
  BusyProcesses(const BusyProcesses&) = delete;
  BusyProcesses& operator=(const BusyProcesses&) = delete;
  [[nodiscard]] std::size_t size() const { return pids_.size(); }

 private:
  std::vector<pid_t> pids_;
};

struct Case {
  char morphology;
  std::vector<Eigen::Vector2d> areas;  // (y, z) on the wall
};

}  // namespace

using fixtures::generous;

class MorphologyPlans : public ::testing::TestWithParam<Case> {};

TEST_P(MorphologyPlans, DrillingApproachesAreCollisionFreeAndWithinLimits) {
  const Case c = GetParam();
  Params params = generous(17);
  Planner planner(params);
  planner.set_model(morphology(c.morphology, 4));
  const World world = site(2.2);
  planner.set_environment(environment_of(world, params));
  const auto model = planner.model();
  const Eigen::VectorXd start = start_state(*model);
  PlanRequest req;
  req.request_id = 1;
  req.model_version = 4;
  for (const Eigen::Vector2d& yz : c.areas) req.goals.push_back({fixtures::drilling_area(2.2, yz.x(), yz.y())});
  std::vector<std::size_t> order;
  const PlanResult res = planner.plan(req, start, [&](const GoalResult& g) { order.push_back(g.index); });
  ASSERT_EQ(res.goals.size(), c.areas.size());
  EXPECT_EQ(res.status, Status::kSucceeded) << res.reason;
  for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i) << "goals not reported in FIFO order";
  Eigen::VectorXd from = start;
  for (std::size_t g = 0; g < res.goals.size(); ++g) {
    const GoalResult& r = res.goals[g];
    ASSERT_EQ(r.status, Status::kSucceeded) << "goal " << g << ": " << r.reason;
    const int n = recheck(*model, environment_of(world, params), params, r, from, req.goals[g].area);
    EXPECT_GT(n, 10);
    from = model->to_full(r.trajectory.points.back().q, from);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Paper, MorphologyPlans,
    ::testing::Values(Case{'a', {{0.0, 1.9}, {0.4, 2.3}, {-0.4, 2.1}}}, Case{'b', {{0.0, 2.2}, {-0.3, 2.6}, {0.4, 2.0}}}),
    [](const ::testing::TestParamInfo<Case>& i) { return std::string("morphology_") + i.param.morphology; });

// The planner's budgets are CPU time of its thread: two busy processes beside it (on this
// 2-core machine: each core shared) make a plan slower, never different. The shipped budgets,
// not the generous ones the other tests use.
TEST(Planner, APlanIsTheSameWithTwoBusyProcessesBesideIt) {
  Params params;
  params.seed = 31;
  const auto plan_once = [&] {
    Planner planner(params);
    planner.set_model(morphology('a', 4));
    planner.set_environment(environment_of(site(2.2), params));
    PlanRequest req;
    req.request_id = 1;
    req.model_version = 4;
    req.goals.push_back({fixtures::drilling_area(2.2, 0.0, 1.9)});
    req.goals.push_back({fixtures::drilling_area(2.2, 0.4, 2.3)});
    return planner.plan(req, start_state(*planner.model()), [](const GoalResult&) {});
  };
  const PlanResult quiet = plan_once();
  ASSERT_EQ(quiet.status, Status::kSucceeded) << quiet.reason;
  PlanResult loaded;
  {
    const BusyProcesses busy(2);
    ASSERT_EQ(busy.size(), 2u) << "could not start the busy processes";
    loaded = plan_once();
  }
  ASSERT_EQ(loaded.status, quiet.status) << loaded.reason;
  ASSERT_EQ(loaded.goals.size(), quiet.goals.size());
  for (std::size_t g = 0; g < quiet.goals.size(); ++g) {
    const Trajectory& a = quiet.goals[g].trajectory;
    const Trajectory& b = loaded.goals[g].trajectory;
    ASSERT_EQ(b.points.size(), a.points.size()) << "goal " << g;
    for (std::size_t i = 0; i < a.points.size(); ++i) {
      EXPECT_EQ(b.points[i].time, a.points[i].time) << "goal " << g << " sample " << i;
      EXPECT_EQ((b.points[i].q - a.points[i].q).cwiseAbs().maxCoeff(), 0.0) << "goal " << g << " sample " << i;
    }
  }
}

TEST(Planner, HotSwapRebuildsTheConfigurationSpace) {
  Params params = generous(23);
  Planner planner(params);
  const World world = site(2.0);
  planner.set_environment(environment_of(world, params));
  planner.set_model(morphology('a', 7));
  const Eigen::Isometry3d high = fixtures::drilling_area(2.0, 0.0, 2.2);
  PlanRequest req{1, 7, "", {{high}}};
  const PlanResult a = planner.plan(req, start_state(*planner.model()), {});
  // Swap: the second passive link is bolted in, modelgen publishes version 8.
  planner.set_model(morphology('b', 8));
  EXPECT_EQ(planner.model_version(), 8u);
  const PlanResult stale = planner.plan(req, start_state(*planner.model()), {});
  EXPECT_EQ(stale.status, Status::kStaleModel);
  EXPECT_NE(stale.reason.find("version 7"), std::string::npos) << stale.reason;
  EXPECT_NE(stale.reason.find("version 8"), std::string::npos) << stale.reason;
  req.model_version = 8;
  const auto model_b = planner.model();
  const PlanResult b = planner.plan(req, start_state(*model_b), {});
  ASSERT_EQ(b.status, Status::kSucceeded) << b.reason;
  recheck(*model_b, environment_of(world, params), params, b.goals[0], start_state(*model_b), high);
  // Both models plan the goal; after the swap the trajectory has the new model's joints and
  // ends on B's longer arm.
  if (a.status == Status::kSucceeded) {
    EXPECT_GT((a.goals[0].goal_q - b.goals[0].goal_q).norm(), 1e-3);
  }
}

// After a task the arm stands where the task left it; nav drives with it home (its transport
// posture, the footprint's). A home request plans the arm there from a drilling posture, the base
// standing, collision free and within the limits, and ends on the SRDF's home values.
TEST(Planner, AHomeRequestTakesTheArmToItsHomingPostureTheBaseStanding) {
  const Params params = generous(31);
  auto planner = planner_at_site(params, 'a', 4);
  const auto model = planner->model();
  ASSERT_FALSE(model->robot().home().empty()) << "the generated SRDF has no home group state";
  const Eigen::Isometry3d area = fixtures::drilling_area(2.2, 0.3, 1.0);
  const PlanResult approach = planner->plan(PlanRequest{1, 4, "", {{area}}}, start_state(*model), {});
  ASSERT_EQ(approach.status, Status::kSucceeded) << approach.reason;
  const Eigen::VectorXd drilling = model->to_full(approach.goals[0].trajectory.points.back().q, start_state(*model));

  PlanRequest home{2, 4, "", {}};
  home.home = true;
  const PlanResult r = planner->plan(home, drilling, {});
  ASSERT_EQ(r.status, Status::kSucceeded) << r.reason;
  ASSERT_EQ(r.goals.size(), 1u);
  const Trajectory& t = r.goals[0].trajectory;
  ASSERT_GE(t.points.size(), 2u);
  EXPECT_LT((t.points.front().q - model->to_planned(drilling)).norm(), 1e-9);
  const Eigen::VectorXd end = t.points.back().q;
  double moved = 0.0;
  for (Eigen::Index j = 3; j < end.size(); ++j) {
    const std::string& name = model->joint_names()[static_cast<std::size_t>(j)];
    const double expected = std::clamp(model->robot().home(name).value_or(0.0), model->lower()[j], model->upper()[j]);
    EXPECT_NEAR(end[j], expected, 1e-9) << name;
    moved = std::max(moved, std::abs(drilling[model->planned_indices()[static_cast<std::size_t>(j)]] - expected));
  }
  EXPECT_GT(moved, 0.3) << "the drilling posture was already home: the test proves nothing";
  StateChecker exact(model, environment_of(site(2.2), params), params, 0.0);
  for (const TrajectoryPoint& p : t.points) {
    EXPECT_EQ(p.q.head<3>(), model->to_planned(drilling).head<3>()) << "the base moved at " << p.time << " s";
    const Validity v = exact.check(model->to_full(p.q, drilling));
    EXPECT_TRUE(v.valid()) << p.time << " s: " << to_string(v.constraint) << ": " << v.detail;
  }
  EXPECT_TRUE(t.points.back().qd.isZero());
  EXPECT_FALSE(r.goals[0].drives.empty());

  // Already home: the request succeeds where the arm stands.
  const PlanResult again = planner->plan(home, model->to_full(end, drilling), {});
  ASSERT_EQ(again.status, Status::kSucceeded) << again.reason;
  EXPECT_LT((again.goals[0].trajectory.points.back().q - end).norm(), 1e-9);

  // Home with goals is a malformed request; home where the homing posture meets a wall is
  // refused naming what it meets.
  PlanRequest both = home;
  both.goals = {{area}};
  const PlanResult malformed = planner->plan(both, drilling, {});
  EXPECT_EQ(malformed.status, Status::kInvalidRequest);
  EXPECT_NE(malformed.reason.find("home"), std::string::npos) << malformed.reason;
  Planner blocked(params);
  blocked.set_model(morphology('a', 4));
  // A crate where the homing posture puts the tool, over the base, clear of the drilling posture.
  const Eigen::Vector3d tool_home = model->link_pose(model->to_full(end, drilling), model->tool("").frame).translation();
  World crate = site(2.2);
  crate.boxes.push_back({"crate", Eigen::Vector3d(0.15, 0.15, 0.15), tool_home, 0.0});
  blocked.set_environment(environment_of(crate, params));
  const PlanResult no_home = blocked.plan(home, drilling, {});
  EXPECT_EQ(no_home.status, Status::kUnreachable) << no_home.reason;
  EXPECT_NE(no_home.reason.find("home: the homing posture is rejected where the robot stands by environment collision"),
            std::string::npos)
      << no_home.reason;
}

// A task that starts from a posture of its own (collab's carrying posture) asks for it by joint:
// the named joints end on the positions asked, the others where they stood, the base standing,
// every sample collision free and within the limits. A name the model has no arm joint for, a
// position beyond its limits, a joint named twice, or goals beside it are refused naming what.
TEST(Planner, APostureRequestTakesTheNamedJointsThereTheRestStanding) {
  const Params params = generous(37);
  auto planner = planner_at_site(params, 'a', 4);
  const auto model = planner->model();
  const Eigen::VectorXd start = start_state(*model);
  PlanRequest home{1, 4, "", {}};
  home.home = true;
  const PlanResult at_home = planner->plan(home, start, {});
  ASSERT_EQ(at_home.status, Status::kSucceeded) << at_home.reason;
  const Eigen::VectorXd from = model->to_full(at_home.goals[0].trajectory.points.back().q, start);
  const Eigen::VectorXd planned_from = model->to_planned(from);

  // Two arm joints halfway towards a limit each.
  const std::string a = model->joint_names()[4];
  const std::string b = model->joint_names()[6];
  const double a_to = 0.5 * (planned_from[4] + model->upper()[4]);
  const double b_to = 0.5 * (planned_from[6] + model->lower()[6]);
  ASSERT_GT(std::abs(a_to - planned_from[4]) + std::abs(b_to - planned_from[6]), 0.3)
      << "the posture is where the arm stands: the test proves nothing";
  PlanRequest posture{2, 4, "", {}};
  posture.posture = {{a, a_to}, {b, b_to}};
  const PlanResult r = planner->plan(posture, from, {});
  ASSERT_EQ(r.status, Status::kSucceeded) << r.reason;
  ASSERT_EQ(r.goals.size(), 1u);
  const Trajectory& t = r.goals[0].trajectory;
  ASSERT_GE(t.points.size(), 2u);
  const Eigen::VectorXd end = t.points.back().q;
  for (Eigen::Index j = 0; j < end.size(); ++j) {
    const double expected = j == 4 ? a_to : j == 6 ? b_to : planned_from[j];
    EXPECT_NEAR(end[j], expected, 1e-9) << model->joint_names()[static_cast<std::size_t>(j)];
  }
  StateChecker exact(model, environment_of(site(2.2), params), params, 0.0);
  for (const TrajectoryPoint& p : t.points) {
    EXPECT_EQ(p.q.head<3>(), planned_from.head<3>()) << "the base moved at " << p.time << " s";
    const Validity v = exact.check(model->to_full(p.q, from));
    EXPECT_TRUE(v.valid()) << p.time << " s: " << to_string(v.constraint) << ": " << v.detail;
  }
  EXPECT_TRUE(t.points.back().qd.isZero());

  const auto refused = [&](std::vector<std::pair<std::string, double>> joints, std::vector<Goal> goals = {}) {
    PlanRequest bad{3, 4, "", std::move(goals)};
    bad.posture = std::move(joints);
    const PlanResult out = planner->plan(bad, from, {});
    EXPECT_EQ(out.status, Status::kInvalidRequest) << out.reason;
    EXPECT_TRUE(out.goals.empty());
    return out.reason;
  };
  EXPECT_NE(refused({{"J9_Z", 0.1}}).find("'J9_Z' is not an arm joint of model version 4 (its arm joints: " +
                                           model->joint_names()[3]),
            std::string::npos);
  EXPECT_NE(refused({{"base_x", 0.1}}).find("'base_x' is not an arm joint"), std::string::npos);
  std::ostringstream beyond;
  beyond << "joint '" << a << "' to " << model->upper()[4] + 0.1 << " is beyond its limits [";
  EXPECT_NE(refused({{a, model->upper()[4] + 0.1}}).find(beyond.str()), std::string::npos) << beyond.str();
  EXPECT_NE(refused({{a, std::nan("")}}).find("is beyond its limits"), std::string::npos);
  EXPECT_NE(refused({{a, a_to}, {a, a_to}}).find("joint '" + a + "' is named twice"), std::string::npos);
  EXPECT_NE(refused({{a, a_to}}, {{fixtures::drilling_area(2.2, 0.3, 1.0)}}).find("a posture request has no goals"),
            std::string::npos);
}

TEST(Planner, ClearErrorsForBadRequests) {
  Params params;
  Planner planner(params);
  PlanRequest req{5, 1, "", {{fixtures::drilling_area(2.0, 0.0, 1.0)}}};
  const PlanResult none = planner.plan(req, Eigen::VectorXd::Zero(3), {});
  EXPECT_EQ(none.status, Status::kNoModel);
  planner.set_model(morphology('a', 1));
  const auto model = planner.model();
  const Eigen::VectorXd start = start_state(*model);

  // A wall 6 m up: no posture can put the camera there.
  PlanRequest far = req;
  far.goals = {{fixtures::drilling_area(2.0, 0.0, 6.0)}};
  const PlanResult unreachable = planner.plan(far, start, {});
  EXPECT_EQ(unreachable.status, Status::kUnreachable);
  EXPECT_NE(unreachable.reason.find("camera_E"), std::string::npos) << unreachable.reason;

  PlanRequest empty = req;
  empty.goals.clear();
  EXPECT_EQ(planner.plan(empty, start, {}).status, Status::kInvalidRequest);
  PlanRequest tool = req;
  tool.end_effector = "sander_E";
  const PlanResult bad_tool = planner.plan(tool, start, {});
  EXPECT_EQ(bad_tool.status, Status::kInvalidRequest);
  EXPECT_NE(bad_tool.reason.find("sander_E"), std::string::npos) << bad_tool.reason;
  EXPECT_EQ(planner.plan(req, Eigen::VectorXd::Zero(4), {}).status, Status::kInvalidStart);
  PlanRequest nan_tip = req;
  nan_tip.tip_distance = std::nan("");
  const PlanResult bad_tip = planner.plan(nan_tip, start, {});
  EXPECT_EQ(bad_tip.status, Status::kInvalidRequest);
  EXPECT_NE(bad_tip.reason.find("tip_distance"), std::string::npos) << bad_tip.reason;

  // Start state in collision: the base stands inside the wall.
  Environment env(params.octomap_resolution);
  World w;
  w.boxes.push_back(fixtures::wall_at(0.2));
  env.add_world(w);
  planner.set_environment(env);
  const PlanResult bad_start = planner.plan(req, start, {});
  EXPECT_EQ(bad_start.status, Status::kInvalidStart) << bad_start.reason;
  EXPECT_NE(bad_start.reason.find("environment collision"), std::string::npos) << bad_start.reason;

  // A failed model keeps the previous one.
  ModelDescription broken = morphology('b', 2);
  broken.urdf = "<robot name=\"x\"/>";
  EXPECT_THROW(planner.set_model(broken), PlannerError);
  EXPECT_EQ(planner.model_version(), 1u);
}

// The drill's hole postures (PlanRequest::tip_distance): the bit's tip, not the camera, goes on
// the hole's axis, so the posture checked against the torque limits with the drilling force is
// the one drilled from. With the camera on the axis the bit stood 0.11 m beside the hole (the
// drill module's camera sits above the bit), and the alignment's Cartesian move reached out to
// an unchecked posture: on morphology A the shoulder J2_E then needed its peak torque in the
// BIM scenario and the safety layer stopped the robot.
TEST(Planner, ATipTaskPutsTheBitOnTheHolesAxisAndChecksItsTorques) {
  Params params = generous(23);
  auto planner = planner_at_site(params, 'a', 3);
  const auto model = planner->model();
  const Eigen::VectorXd start = start_state(*model);
  const Eigen::Isometry3d hole = fixtures::drilling_area(2.2, 0.1, 1.2);
  const Eigen::Vector3d n = hole.linear().col(2);
  const EndEffectorInfo& tool = model->tool("");
  const auto lateral = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - hole.translation();
    return (d - d.dot(n) * n).norm();
  };
  for (const bool tip : {false, true}) {
    SCOPED_TRACE(tip ? "tip task" : "camera task");
    PlanRequest req{9, 3, "", {{hole}}};
    if (tip) req.tip_distance = 0.07;
    else req.camera_distance = 0.23;
    const PlanResult res = planner->plan(req, start, {});
    ASSERT_EQ(res.status, Status::kSucceeded) << res.reason;
    const Eigen::VectorXd end = model->to_full(res.goals[0].trajectory.points.back().q, start);
    const Eigen::Isometry3d bit = model->link_pose(end, tool.frame);
    const Eigen::Isometry3d camera = model->link_pose(end, model->camera_frame(tool));
    if (tip) {
      EXPECT_LT(lateral(bit.translation()), 5e-3) << "the bit is off the hole's axis";
      EXPECT_NEAR((bit.translation() - hole.translation()).dot(n), 0.07, 5e-3);
      EXPECT_GT(bit.linear().col(2).dot(-n), std::cos(5e-3)) << "the bit does not point into the wall";
      // The camera looks along the bit from beside it.
      EXPECT_GT(lateral(camera.translation()), 0.08);
    } else {
      EXPECT_LT(lateral(camera.translation()), 5e-3);
      // The bit stands off the hole's axis by its offset from the camera's optical axis (the
      // drill module: 4.5 cm, the camera pitched towards the bit).
      const Eigen::Vector3d d = bit.translation() - camera.translation();
      const Eigen::Vector3d z = camera.linear().col(2);
      const double offset = (d - d.dot(z) * z).norm();
      EXPECT_GT(offset, 0.03);
      EXPECT_NEAR(lateral(bit.translation()), offset, 5e-3)
          << "the camera task leaves the bit beside the hole";
    }
    // The posture holds with the drilling force on the bit.
    StateChecker exact(model, environment_of(site(2.2), params), params, 0.0);
    const Validity v = exact.check(end, tool.frame);
    EXPECT_TRUE(v.valid()) << to_string(v.constraint) << ": " << v.detail;
  }
  // With the bit's reach: the arm's torques hold where the bit ends, 0.1 m on into the wall,
  // the base standing (the torques computed here by the checker at that posture).
  PlanRequest reach{11, 3, "", {{hole}}};
  reach.tip_distance = 0.07;
  reach.tip_reach = 0.1;
  const PlanResult reached = planner->plan(reach, start, {});
  ASSERT_EQ(reached.status, Status::kSucceeded) << reached.reason;
  const Eigen::VectorXd posture = model->to_full(reached.goals[0].trajectory.points.back().q, start);
  const std::optional<Eigen::VectorXd> in_hole = reached_posture(*model, posture, tool.frame, -n, 0.1);
  ASSERT_TRUE(in_hole.has_value());
  const Eigen::Isometry3d bit = model->link_pose(*in_hole, tool.frame);
  EXPECT_NEAR((bit.translation() - hole.translation()).dot(n), -0.03, 1e-3) << "the bit is not 3 cm into the wall";
  EXPECT_LT(lateral(bit.translation()), 1e-3);
  EXPECT_TRUE(model->to_planned(*in_hole).head(3).isApprox(model->to_planned(posture).head(3)))
      << "the base moved";
  StateChecker torques(model, environment_of(site(2.2), params), params, 0.0);
  for (const std::string& contact : {tool.frame, std::string()}) {
    const Eigen::VectorXd tau = torques.required_torques(*in_hole, contact);
    for (Eigen::Index i = 0; i < tau.size(); ++i) {
      const double limit = model->torque_limits()[i];
      if (limit > 0.0) {
        EXPECT_LE(std::abs(tau[i]), limit * params.torque_margin) << "joint " << i << contact;
      }
    }
  }
  // A reach the arm cannot make is refused with the reason.
  reach.tip_reach = 0.9;
  const PlanResult too_far = planner->plan(reach, start, {});
  EXPECT_EQ(too_far.status, Status::kUnreachable);
  EXPECT_NE(too_far.reason.find("bit reach x"), std::string::npos) << too_far.reason;
  reach.tip_reach = -0.1;
  EXPECT_EQ(planner->plan(reach, start, {}).status, Status::kInvalidRequest);

  PlanRequest unreachable{10, 3, "", {{fixtures::drilling_area(2.2, 0.0, 6.0)}}};
  unreachable.tip_distance = 0.07;
  const PlanResult far = planner->plan(unreachable, start, {});
  EXPECT_EQ(far.status, Status::kUnreachable);
  EXPECT_NE(far.reason.find("tip 'tcp_E'"), std::string::npos) << far.reason;
}

// The drilling force comes with the request (PlanRequest::contact_force; the drill service
// sends its thrust bound, 125 N): the posture found holds with it, a force no arm holds leaves
// no posture, and a force that is no sane number of newtons is refused. The result names the
// posture's heaviest load.
TEST(Planner, TheRequestsContactForceIsTheOneChecked) {
  Params params = generous(23);
  auto planner = planner_at_site(params, 'a', 3);
  const auto model = planner->model();
  const Eigen::VectorXd start = start_state(*model);
  const Eigen::Isometry3d hole = fixtures::drilling_area(2.2, 0.1, 1.2);
  const EndEffectorInfo& tool = model->tool("");
  PlanRequest req{12, 3, "", {{hole}}};
  req.tip_distance = 0.07;
  req.contact_force = 125.0;
  const PlanResult res = planner->plan(req, start, {});
  ASSERT_EQ(res.status, Status::kSucceeded) << res.reason;
  const Eigen::VectorXd end = model->to_full(res.goals[0].trajectory.points.back().q, start);
  Params at_force = params;
  at_force.contact_force = 125.0;
  StateChecker exact(model, environment_of(site(2.2), at_force), at_force, 0.0);
  const Validity v = exact.check(end, tool.frame);
  EXPECT_TRUE(v.valid()) << to_string(v.constraint) << ": " << v.detail;
  EXPECT_NE(res.goals[0].load.find("with the drilling force"), std::string::npos)
      << res.goals[0].load;
  EXPECT_EQ(res.goals[0].load.rfind("J", 0), 0u) << "no joint named: " << res.goals[0].load;

  req.request_id = 13;
  req.contact_force = 1900.0;
  const PlanResult heavy = planner->plan(req, start, {});
  EXPECT_EQ(heavy.status, Status::kUnreachable) << "1900 N held?";
  EXPECT_NE(heavy.reason.find("torque"), std::string::npos) << heavy.reason;

  for (const double bad : {std::nan(""), 2500.0}) {
    req.contact_force = bad;
    const PlanResult refused = planner->plan(req, start, {});
    EXPECT_EQ(refused.status, Status::kInvalidRequest) << bad;
    EXPECT_NE(refused.reason.find("contact_force"), std::string::npos) << refused.reason;
  }
}

TEST(Planner, ObstacleFromAPointCloudIsAvoided) {
  Params params = generous(31);
  Planner planner(params);
  planner.set_model(morphology('a', 1));
  // A wall seen by a lidar as points (5 cm grid), plus a box of points in front of it.
  std::vector<Eigen::Vector3d> points;
  for (double y = -2.0; y <= 2.0; y += 0.04) {
    for (double z = 0.0; z <= 3.0; z += 0.04) points.emplace_back(2.0, y, z);
  }
  for (double x = 1.0; x <= 1.3; x += 0.04) {
    for (double y = 0.5; y <= 0.9; y += 0.04) {
      for (double z = 0.0; z <= 0.8; z += 0.04) points.emplace_back(x, y, z);
    }
  }
  Environment env(params.octomap_resolution);
  env.insert_point_cloud(points, Eigen::Vector3d(0.0, 0.0, 1.0), 10.0);
  EXPECT_GT(env.occupied_cells(), 3000u);
  EXPECT_TRUE(env.occupied({2.0, 0.0, 1.5}));
  EXPECT_FALSE(env.occupied({1.0, 0.0, 1.5}));
  planner.set_environment(env);
  const auto model = planner.model();
  const Eigen::VectorXd start = start_state(*model);
  const Eigen::Isometry3d area = fixtures::drilling_area(2.0, 0.0, 2.0);
  const PlanResult r = planner.plan({2, 1, "", {{area}}}, start, {});
  ASSERT_EQ(r.status, Status::kSucceeded) << r.reason;
  recheck(*model, env, params, r.goals[0], start, area);
  EXPECT_THROW(env.insert_point_cloud({Eigen::Vector3d(0, 0, std::nan(""))}, Eigen::Vector3d::Zero()), PlannerError);
}

TEST(Planner, WarmUpFillsThePostureMemoryAndPlansStayValid) {
  Params params = generous(23);
  const auto planner = planner_at_site(params, 'a', 9);
  // Mid heights on a bare wall: every one has goal postures.
  EXPECT_EQ(planner->warm_up(1.0, 1.4, 0.2, 15.0), 3);
  // No model: nothing to warm up.
  EXPECT_EQ(Planner(params).warm_up(1.0, 1.4, 0.2, 1.0), 0);
  // Goals near the remembered heights plan (seeded from memory) and re-check densely.
  const World world = site(2.2);
  const auto model = planner->model();
  const Eigen::VectorXd start = start_state(*model);
  PlanRequest req{5, 9, "", {{fixtures::drilling_area(2.2, 0.2, 1.1)}, {fixtures::drilling_area(2.2, -0.3, 1.3)}}};
  const PlanResult res = planner->plan(req, start);
  ASSERT_EQ(res.status, Status::kSucceeded) << res.reason;
  Eigen::VectorXd from = start;
  for (std::size_t g = 0; g < res.goals.size(); ++g) {
    EXPECT_GT(recheck(*model, environment_of(world, params), params, res.goals[g], from, req.goals[g].area), 10);
    from = model->to_full(res.goals[g].trajectory.points.back().q, from);
  }
}

// A crew swaps the drill off and back on: the model that comes back (a new version, the same
// content hash) gets back the postures it remembered and the heights its warm-up searched, so
// the first approach after the swap starts from them instead of from random seeds.
TEST(Planner, ASwapBackToAModelKeepsItsPostureMemory) {
  Params params = generous(23);
  const ModelDescription a = morphology('a', 9);
  ASSERT_FALSE(a.content_hash.empty());
  Planner planner(params);
  planner.set_environment(environment_of(site(2.2), params));
  planner.set_model(a);
  EXPECT_EQ(planner.remembered(), 0u);
  ASSERT_EQ(planner.warm_up(1.0, 1.4, 0.2, 15.0), 3);
  const std::size_t warmed = planner.remembered();
  ASSERT_GT(warmed, 0u);
  // Another model: its own, empty memory.
  planner.set_model(morphology('b', 10));
  EXPECT_EQ(planner.remembered(), 0u);
  // A back (version 11): its postures, and a warm-up with no time finds every height searched.
  ModelDescription a_again = a;
  a_again.version = 11;
  planner.set_model(a_again);
  EXPECT_EQ(planner.remembered(), warmed);
  EXPECT_EQ(planner.warm_up(1.0, 1.4, 0.2, 0.0), 3);
  // A height no warm-up searched is searched (and with no time, found nowhere).
  EXPECT_EQ(planner.warm_up(1.6, 1.6, 0.2, 0.0), 0);
  // A new version of the same model keeps the memory as it is.
  a_again.version = 12;
  planner.set_model(a_again);
  EXPECT_EQ(planner.remembered(), warmed);
  // memory_models: 1 keeps no other model's memory.
  params.memory_models = 1;
  Planner forgetful(params);
  forgetful.set_model(a);
  ASSERT_EQ(forgetful.warm_up(1.2, 1.2, 0.2, 15.0), 1);
  ASSERT_GT(forgetful.remembered(), 0u);
  forgetful.set_model(morphology('b', 10));
  forgetful.set_model(a_again);
  EXPECT_EQ(forgetful.remembered(), 0u);
  EXPECT_EQ(forgetful.warm_up(1.2, 1.2, 0.2, 0.0), 0);
}

// The service's warm-up ends when the service stops: within a height's search, not after it
// (each costs seconds of CPU, minutes at nice 19 on a loaded PC), and the height cut short is
// searched again by the next warm-up.
TEST(Planner, WarmUpStopsWithinAHeightsSearchAndSearchesItAgainLater) {
  Params params = generous(23);
  Planner planner(params);
  planner.set_model(morphology('a', 9));
  int asked = 0;
  EXPECT_EQ(planner.warm_up(1.2, 1.2, 0.2, 15.0, [&] { return ++asked == 1; }), 0);
  // Asked before the height, then before each seed: the first seed's "no" ends it.
  EXPECT_LE(asked, 3);
  EXPECT_EQ(planner.remembered(), 0u);
  EXPECT_EQ(planner.warm_up(1.2, 1.2, 0.2, 15.0), 1);
  EXPECT_GT(planner.remembered(), 0u);
}

namespace {

// Morphology A (seed 5) before a low area on a bare wall 2.2 m ahead: the goal posture found
// there, and the wall with a crate where that posture's base stands (the posture, remembered
// and placed as it is, collides).
struct BlockedLowArea {
  Params params;
  std::shared_ptr<const PlanningModel> model;
  Eigen::VectorXd start;
  Eigen::Isometry3d area;
  World bare, blocked;
  PostureResult first;  // on the bare wall
};

BlockedLowArea blocked_low_area(double lateral) {
  BlockedLowArea s;
  s.params.seed = 5;
  s.model = PlanningModel::build(morphology('a', 1), s.params);
  s.start = start_state(*s.model);
  s.area = fixtures::drilling_area(2.2, lateral, 0.55);
  s.bare.boxes.push_back(fixtures::wall_at(2.2));
  StateChecker bare_checker(s.model, environment_of(s.bare, s.params), s.params, s.params.environment_padding);
  s.first = generate_posture(*s.model, bare_checker, s.params, s.model->tool(""), s.start, s.area, 1);
  EXPECT_TRUE(s.first.found) << s.first.reason;
  s.blocked = s.bare;
  if (!s.first.found) return s;
  s.blocked.boxes.push_back({"crate", Eigen::Vector3d(0.5, 0.5, 0.4), Eigen::Vector3d(s.first.q[0], s.first.q[1], 0.2), 0.0});
  StateChecker checker(s.model, environment_of(s.blocked, s.params), s.params, s.params.environment_padding);
  EXPECT_FALSE(checker.check(s.model->to_full(s.first.q, s.start)).valid());
  return s;
}

// Only the seeds before the random ones: nspg_seeds ends the search, not the clock.
Params without_random_seeds(const Params& params, int seeds) {
  Params few = params;
  few.nspg_seeds = seeds;
  few.nspg_time = 60.0;
  return few;
}

}  // namespace

TEST(Planner, MirroredHintStandsOnTheAreasOtherSide) {
  BlockedLowArea s = blocked_low_area(0.0);
  ASSERT_TRUE(s.first.found);
  ASSERT_GT(std::abs(s.first.q[1]), 0.2) << "a low area: the base stands beside it";
  const EndEffectorInfo& tool = s.model->tool("");
  // The whole of that side of the area is blocked (not only where the base stood: the start
  // posture, placed, found room beside the crate): only the other side is left.
  const double side = s.first.q[1] > 0.0 ? 1.0 : -1.0;
  s.blocked.boxes.push_back({"fence", Eigen::Vector3d(1.2, 2.0, 0.6),
                             Eigen::Vector3d(1.5, side * 1.5, 0.3), 0.0});
  // Seeds: the start posture placed and as it is, the hint, its mirror image; nothing else.
  StateChecker checker(s.model, environment_of(s.blocked, s.params), s.params, s.params.environment_padding);
  const Eigen::VectorXd hint = s.first.q.tail(s.first.q.size() - 3);
  const PostureResult mirrored =
      generate_posture(*s.model, checker, without_random_seeds(s.params, 2 + 1 + 1), tool, s.start, s.area, 1, {hint});
  ASSERT_TRUE(mirrored.found) << mirrored.reason;
  EXPECT_LT(mirrored.q[1] * s.first.q[1], 0.0) << "the base should stand on the other side of the area";
  // Which of the four seeds finds it is not asserted: with the drill camera pitched 20 deg
  // the start posture, placed, also fits on that side (found by the second seed), so the
  // mirror seed's own result (the hint's image) is not reached here. TODO(#17): a case where
  // only the image fits.
  StateChecker exact(s.model, environment_of(s.blocked, s.params), s.params, 0.0);
  EXPECT_TRUE(exact.check(s.model->to_full(mirrored.q, s.start), tool.frame).valid());
  EXPECT_TRUE(exact.check(s.model->to_full(mirrored.q, s.start)).valid());
}

TEST(Planner, ResumedPostureSearchGoesOnFromLaterSeedsOnTheTask) {
  // When no path reaches a goal posture, the planner asks for another from the seed after the
  // one that gave it: later seeds, still valid, the camera on the task (not turned away from the
  // wall: with the axis as a cross product, the resumed search found such a posture). Later seeds
  // may converge to the same posture; Planner::plan skips postures of an unreached shape.
  const BlockedLowArea s = blocked_low_area(0.0);
  ASSERT_TRUE(s.first.found);
  const EndEffectorInfo& tool = s.model->tool("");
  Params params = s.params;
  params.nspg_time = 60.0;  // the seeds end it, not the clock
  StateChecker checker(s.model, environment_of(s.bare, params), params, params.environment_padding);
  const std::vector<Eigen::VectorXd> hints{s.first.q.tail(s.first.q.size() - 3)};
  const PostureResult a = generate_posture(*s.model, checker, params, tool, s.start, s.area, 1, hints);
  ASSERT_TRUE(a.found) << a.reason;
  EXPECT_EQ(a.next_seed, a.candidates);
  const PostureResult b = generate_posture(*s.model, checker, params, tool, s.start, s.area, 1, hints, a.next_seed);
  ASSERT_TRUE(b.found) << b.reason;
  EXPECT_GT(b.next_seed, a.next_seed);
  EXPECT_EQ(b.next_seed - a.next_seed, b.candidates);
  StateChecker exact(s.model, environment_of(s.bare, params), params, 0.0);
  for (const PostureResult* r : {&a, &b}) {
    const Eigen::VectorXd full = s.model->to_full(r->q, s.start);
    EXPECT_TRUE(exact.check(full, tool.frame).valid());
    const auto [position, angle] = task_error(*s.model, params, tool, full, s.area);
    EXPECT_LT(position, 2e-3);
    EXPECT_LT(angle, 2e-3) << "the camera looks away from the area";
  }
}

TEST(Planner, TurnedHintGetsPastAnObstacleThatBlocksItsBase) {
  const BlockedLowArea s = blocked_low_area(0.3);
  ASSERT_TRUE(s.first.found);
  const EndEffectorInfo& tool = s.model->tool("");
  const Eigen::VectorXd hint = s.first.q.tail(s.first.q.size() - 3);
  const Eigen::VectorXd image = *s.model->mirrored_arm(hint);
  // Every seed before the random ones (the start posture placed and as it is, the hint and its
  // image, then the first joint turned either way, at most 5 steps each for the start posture,
  // the hint and the image), all valid postures kept: some are the hint or its image turned,
  // past the crate.
  Params all = without_random_seeds(s.params, 2 + 2 + 2 * 3 * 5);
  all.nspg_enough = 1000;
  StateChecker checker(s.model, environment_of(s.blocked, s.params), s.params, s.params.environment_padding);
  const PostureResult r = generate_posture(*s.model, checker, all, tool, s.start, s.area, 1, {hint});
  StateChecker exact(s.model, environment_of(s.blocked, s.params), s.params, 0.0);
  int turned = 0;
  for (const Eigen::VectorXd& q : r.valid) {
    const Eigen::VectorXd arm = q.tail(hint.size());
    for (const Eigen::VectorXd* family : {&hint, &image}) {
      const bool same_shape = (arm.tail(hint.size() - 1) - family->tail(hint.size() - 1)).cwiseAbs().maxCoeff() < 0.3;
      if (!same_shape || std::abs(arm[0] - (*family)[0]) < 0.3) continue;
      turned += 1;
      EXPECT_GT((q.head<2>() - s.first.q.head<2>()).norm(), 0.25) << "the base should stand clear of the crate";
      EXPECT_TRUE(exact.check(s.model->to_full(q, s.start), tool.frame).valid());
      EXPECT_TRUE(exact.check(s.model->to_full(q, s.start)).valid());
    }
  }
  EXPECT_GT(turned, 0) << r.valid.size() << " valid postures, none a turned hint or image";
}

TEST(Planner, LongArmReachesALowAreaAndTheArmOnlyPathsStayValid) {
  // Morphology B (2.15 m arm) at a low area: the shoulder's continuous torque leaves the arm a
  // narrow pocket of folded postures. Budget generous so the test does not depend on the
  // machine's speed; whichever path method succeeds, the plan must re-check densely.
  Params params = generous(29);
  const auto planner = planner_at_site(params, 'b', 3);
  const World world = site(2.2);
  const auto model = planner->model();
  const Eigen::VectorXd start = start_state(*model);
  const Eigen::Isometry3d area = fixtures::drilling_area(2.2, 0.0, 0.6);
  const PlanResult res = planner->plan({7, 3, "", {{area}}}, start);
  ASSERT_EQ(res.status, Status::kSucceeded) << res.reason;
  const GoalResult& g = res.goals[0];
  // Here the direct motion and the whole-body projected line fail; the arm-only search finds
  // the way into the pocket.
  EXPECT_TRUE(g.path_method == "arm, then drive" || g.path_method == "drive, then arm") << g.path_method;  // no memory here
  EXPECT_GT(recheck(*model, environment_of(world, params), params, g, start, area), 10) << "path found by " << g.path_method;
}

TEST(Planner, WarmUpRemembersArmPathsThatLaterPlansReplay) {
  // Morphology B: the warm-up stores, with each low posture, the arm's way to it from the
  // parked arm; a later low goal near a box replays it (checked against the map), every time.
  // The warm-up's path searches here take 0.23-4.4 s of CPU: with the service's 0.5 s budget
  // what was remembered depended on the machine's speed (a search of 0.43-0.46 s on this
  // machine ran out on slower ones, and 2 of 5 fresh-clone runs then planned without a replay);
  // generous() gives them 10 s, so the memory, and the plans from it, are the seed's alone.
  Params params = generous(31);
  const auto planner = planner_at_site(params, 'b', 5);
  ASSERT_EQ(planner->warm_up(0.5, 0.7, 0.1, 20.0), 3);
  const World world = site(2.2);
  const auto model = planner->model();
  const Eigen::VectorXd start = start_state(*model);
  const Eigen::Isometry3d area = fixtures::drilling_area(2.2, -0.3, 0.6);
  for (uint64_t id = 8; id < 11; ++id) {
    const PlanResult res = planner->plan({id, 5, "", {{area}}}, start);
    ASSERT_EQ(res.status, Status::kSucceeded) << res.reason;
    const GoalResult& g = res.goals[0];
    EXPECT_NE(g.path_method.find("remembered arm path"), std::string::npos) << "request " << id << ": " << g.path_method;
    EXPECT_GT(recheck(*model, environment_of(world, params), params, g, start, area), 10) << "path found by " << g.path_method;
  }

  // The same warm-up with no time for the arm's ways remembers the postures alone: the plan
  // still succeeds, by a search, and replays nothing.
  params.warm_up_path_time = 0.0;
  const auto forgetful = planner_at_site(params, 'b', 5);
  ASSERT_EQ(forgetful->warm_up(0.5, 0.7, 0.1, 20.0), 3);
  const PlanResult res = forgetful->plan({11, 5, "", {{area}}}, start);
  ASSERT_EQ(res.status, Status::kSucceeded) << res.reason;
  EXPECT_EQ(res.goals[0].path_method.find("remembered arm path"), std::string::npos) << res.goals[0].path_method;
}

// The drill service's second hole on the demo: the base's odometry had drifted a few cm, so the
// planner's start had a leg inside the wall map. Such a start is moved out (nearest clear base
// pose within start_tolerance) and the move prepended; a start deeper inside stays refused.
TEST(Planner, StartSlightlyInsideTheMapIsMovedOutFirst) {
  Params params = generous(41);
  params.environment_padding = 0.0;
  Planner planner(params);
  planner.set_model(morphology('a', 1));
  const auto model = planner.model();
  const Eigen::VectorXd start = start_state(*model);
  // The wall position where the start just touches it (1 cm steps towards the robot).
  double touching = 0.0;
  for (double x = 1.5; x > 0.0; x -= 0.01) {
    World w;
    w.boxes.push_back(fixtures::wall_at(x));
    StateChecker check(model, environment_of(w, params), params, 0.0);
    if (check.check(start).constraint == Constraint::kEnvironmentCollision) {
      touching = x;
      break;
    }
  }
  ASSERT_GT(touching, 0.2);
  const auto at_wall = [&](double x) {
    World w;
    w.boxes.push_back(fixtures::wall_at(x));
    return w;
  };
  // 2 cm inside (the map's 5 cm voxels: the first occupied voxel may come a cell later).
  const World inside = at_wall(touching - 0.02);
  planner.set_environment(environment_of(inside, params));
  const Eigen::Isometry3d area = fixtures::drilling_area(touching - 0.02, 0.0, 1.2);
  const PlanResult r = planner.plan({7, 1, "", {{area}}}, start, {});
  ASSERT_EQ(r.status, Status::kSucceeded) << r.reason;
  EXPECT_NE(r.note.find("the base moved out by"), std::string::npos) << r.note;
  const Trajectory& t = r.goals[0].trajectory;
  ASSERT_GE(t.points.size(), 3u);
  EXPECT_LT((t.points.front().q - model->to_planned(start)).norm(), 1e-9);
  // Past the lead-in, every state is clear of the map: find where the base left the start.
  StateChecker exact(model, environment_of(inside, params), params, 0.0);
  std::size_t clear_from = 0;
  while (clear_from < t.points.size() &&
         !exact.check(model->to_full(t.points[clear_from].q, start)).valid())
    ++clear_from;
  ASSERT_LT(clear_from, t.points.size());
  const Eigen::VectorXd moved = t.points[clear_from].q;
  EXPECT_LE(std::hypot(moved[0] - start[0], moved[1] - start[1]), params.start_tolerance + 1e-9);
  for (std::size_t i = clear_from; i < t.points.size(); ++i) {
    const Validity v = exact.check(model->to_full(t.points[i].q, start));
    EXPECT_TRUE(v.valid()) << "sample " << i << ": " << v.detail;
  }
  // 20 cm inside: refused, naming the collision.
  planner.set_environment(environment_of(at_wall(touching - 0.2), params));
  const PlanResult deep = planner.plan({8, 1, "", {{area}}}, start, {});
  EXPECT_EQ(deep.status, Status::kInvalidStart) << deep.reason;
  EXPECT_NE(deep.reason.find("environment collision"), std::string::npos) << deep.reason;
  // start_tolerance 0: refused too.
  params.start_tolerance = 0.0;
  Planner strict(params);
  strict.set_model(morphology('a', 1));
  strict.set_environment(environment_of(inside, params));
  EXPECT_EQ(strict.plan({9, 1, "", {{area}}}, start, {}).status, Status::kInvalidStart);
}

// After a drilled hole the arm stood a hair inside the planner's conservative link shapes
// (the Cartesian motions leave it a little off the checked posture): the next plan jiggles the
// arm out first. A start folded deep into itself stays refused.
TEST(Planner, StartInSlightSelfCollisionIsJiggledOut) {
  Params params = generous(43);
  Planner planner(params);
  planner.set_model(morphology('a', 1));
  planner.set_environment(environment_of(site(2.2), params));
  const auto model = planner.model();
  const int elbow = model->kinematics().joint_index_or_throw("J4_E");
  StateChecker check(model, environment_of(site(2.2), params), params, 0.0);
  // Fold the elbow until the links touch.
  Eigen::VectorXd folded = start_state(*model);
  double touching = 0.0;
  for (double a = 0.0; std::abs(a) < 3.2; a -= 0.005) {
    folded[elbow] = a;
    const Validity v = check.check(folded);
    if (v.constraint == Constraint::kSelfCollision) {
      touching = a;
      break;
    }
    ASSERT_TRUE(v.valid()) << a << ": " << v.detail;
  }
  ASSERT_NE(touching, 0.0) << "the elbow never folds into the arm";
  const Eigen::Isometry3d area = fixtures::drilling_area(2.2, 0.0, 1.2);
  folded[elbow] = touching - 0.01;
  ASSERT_EQ(check.check(folded).constraint, Constraint::kSelfCollision);
  const PlanResult r = planner.plan({11, 1, "", {{area}}}, folded, {});
  ASSERT_EQ(r.status, Status::kSucceeded) << r.reason;
  EXPECT_NE(r.note.find("self collision"), std::string::npos) << r.note;
  const Trajectory& t = r.goals[0].trajectory;
  EXPECT_LT((t.points.front().q - model->to_planned(folded)).norm(), 1e-9);
  folded[elbow] = touching - 0.3;
  EXPECT_EQ(check.check(folded).constraint, Constraint::kSelfCollision);
  const PlanResult deep = planner.plan({12, 1, "", {{area}}}, folded, {});
  EXPECT_EQ(deep.status, Status::kInvalidStart) << deep.reason;
  EXPECT_NE(deep.reason.find("self collision"), std::string::npos) << deep.reason;
}

// A drive holds a few mrad past the limit a trajectory ended on (the demo's J1_E at -2.7504 rad
// of +-2.75): such a start is clamped onto the limit and planned from, the clamp prepended; a
// start farther out than start_joint_tolerance is refused.
TEST(Planner, StartAHairPastAJointLimitIsClampedFirst) {
  Params params = generous(47);
  Planner planner(params);
  planner.set_model(morphology('a', 1));
  planner.set_environment(environment_of(site(2.2), params));
  const auto model = planner.model();
  const auto& k = model->kinematics();
  const int first = k.joint_index_or_throw("J1_E");
  const auto names = model->joint_names();
  const auto j = static_cast<Eigen::Index>(
      std::find(names.begin(), names.end(), "J1_E") - names.begin());
  ASSERT_LT(j, static_cast<Eigen::Index>(names.size()));
  Eigen::VectorXd past = start_state(*model);
  past[first] = model->lower()[j] - 4e-4;
  StateChecker check(model, environment_of(site(2.2), params), params, 0.0);
  ASSERT_EQ(check.check(past).constraint, Constraint::kJointLimit);
  const Eigen::Isometry3d area = fixtures::drilling_area(2.2, 0.0, 1.2);
  const PlanResult r = planner.plan({13, 1, "", {{area}}}, past, {});
  ASSERT_EQ(r.status, Status::kSucceeded) << r.reason;
  EXPECT_NE(r.note.find("joint limit"), std::string::npos) << r.note;
  const Trajectory& t = r.goals[0].trajectory;
  EXPECT_LT((t.points.front().q - model->to_planned(past)).norm(), 1e-9);
  // From the start onto the limit, never further out, and within the limits from there on.
  bool inside = false;
  for (const TrajectoryPoint& p : t.points) {
    EXPECT_GE(p.q[j], past[first] - 1e-9);
    if (p.q[j] >= model->lower()[j] - 1e-9) inside = true;
    if (inside) {
      EXPECT_GE(p.q[j], model->lower()[j] - 1e-9);
    }
  }
  EXPECT_TRUE(inside);
  past[first] = model->lower()[j] - 0.3;
  const PlanResult far = planner.plan({14, 1, "", {{area}}}, past, {});
  EXPECT_EQ(far.status, Status::kInvalidStart) << far.reason;
  EXPECT_NE(far.reason.find("joint limit"), std::string::npos) << far.reason;
}

// A posture held after a stop may need a hair more than the continuous torque (the chaos test:
// 160.4 N m against 160 on J3_E): such a start is planned from with the limit raised by 5 %,
// and the plan says so; a start 10 % over is refused, naming the torque. The torque limit is
// scaled here so that the start needs 2 % and 10 % more than it, on the arm stretched forward.
TEST(Planner, StartAHairAboveTheContinuousTorqueIsPlannedFromAndFarAboveIsRefused) {
  Params params = generous(53);
  Planner probe(params);
  probe.set_model(morphology('a', 1));
  const auto model = probe.model();
  const auto& k = model->kinematics();
  Eigen::VectorXd start = start_state(*model);
  start[k.joint_index_or_throw("J2_E")] = 0.6;
  start[k.joint_index_or_throw("J4_E")] = -0.3;
  StateChecker checker(model, environment_of(site(2.2), params), params, 0.0);
  ASSERT_TRUE(checker.check(start).valid()) << checker.check(start).detail;
  const Eigen::VectorXd tau = checker.required_torques(start, "");
  double use = 0.0;  // the start's largest fraction of a continuous torque
  for (Eigen::Index i = 0; i < tau.size(); ++i)
    if (model->torque_limits()[i] > 0.0) use = std::max(use, std::abs(tau[i]) / model->torque_limits()[i]);
  std::cout << "the start needs " << use * 100.0 << " % of a continuous torque" << std::endl;
  ASSERT_GT(use, 0.5) << "the arm stretched forward should load its shoulder";
  const Eigen::Isometry3d area = fixtures::drilling_area(2.2, 0.0, 1.2);

  params.torque_margin = use / 1.02;
  Planner slightly(params);
  slightly.set_model(morphology('a', 1));
  slightly.set_environment(environment_of(site(2.2), params));
  ASSERT_EQ(StateChecker(model, environment_of(site(2.2), params), params, 0.0).check(start).constraint,
            Constraint::kTorqueLimit);
  const PlanResult r = slightly.plan({15, 1, "", {{area}}}, start, {});
  EXPECT_NE(r.status, Status::kInvalidStart) << r.reason;  // the goal itself may be out of reach with the scaled limit
  EXPECT_NE(r.note.find("raised by 5 %"), std::string::npos) << r.note;

  params.torque_margin = use / 1.10;
  Planner far(params);
  far.set_model(morphology('a', 1));
  far.set_environment(environment_of(site(2.2), params));
  const PlanResult refused = far.plan({16, 1, "", {{area}}}, start, {});
  EXPECT_EQ(refused.status, Status::kInvalidStart) << refused.reason;
  EXPECT_NE(refused.reason.find("torque"), std::string::npos) << refused.reason;
}
