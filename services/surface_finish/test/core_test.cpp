// The surface finishing core on the paper's spraying morphology (section 6.2: morphology B with
// the Spraying Tool) from both module databases: the public CONCERT database
// (../shared/data/concert_resources) and the project's (data/module_db, deploy/demo/
// spraying_robot.yaml); the sanding robot of the demo (deploy/demo/sanding_robot.yaml).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "finish_fixture.hpp"
#include "surface_finish/admittance.hpp"
#include "surface_finish/areas.hpp"
#include "surface_finish/deposition.hpp"
#include "surface_finish/reach.hpp"
#include "surface_finish/sand_sequence.hpp"
#include "surface_finish/serpentine.hpp"
#include "surface_finish/wall_fit.hpp"

namespace concert::surface_finish {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;


std::shared_ptr<const model::RobotModel> spraying_public() {
  static auto m = test::model_of(fs::path(FINISH_FIXTURES) / "morphology_b_spraying_public.yaml", test::public_db());
  return m;
}
std::shared_ptr<const model::RobotModel> spraying_project() {
  static auto m = test::model_of(test::source_dir() / "deploy/demo/spraying_robot.yaml", test::project_db());
  return m;
}

ToolSpec spray_tool(double overlap = 0.1) { return ToolSpec{Task::kSpray, 0.3, 0.1, overlap}; }

// Areas are deterministic and take a few seconds: computed once per model, at the working
// distance they choose.
const AreaMap& areas_of(Reach& reach, Task task, double standoff) {
  static std::map<std::string, AreaMap> cache;
  const std::string key = reach.model().content_hash() + to_string(task);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, working_areas(reach, task, standoff)).first;
  return it->second;
}
WallFrame wall_of(const Reach& reach, const AreaMap& m) { return WallFrame::ahead(m.wall_distance, reach.standing_height()); }

void print(const AreaMap& m, const std::string& what) {
  std::printf("%s: at %.2f m from the wall, roll %.0f deg, band %s, cells %d x %d\n", what.c_str(), m.wall_distance, m.roll * 180 / M_PI, m.band.str().c_str(),
              m.nx, m.ny);
  for (const Area& a : m.areas) std::printf("  %s %s\n", a.id.c_str(), a.rect.str().c_str());
}

class SprayingMorphologyB : public ::testing::TestWithParam<int> {
 protected:
  std::shared_ptr<const model::RobotModel> model() const { return GetParam() == 0 ? spraying_public() : spraying_project(); }
};

TEST_P(SprayingMorphologyB, HasAreasInFrontOfTheRobotThatItsToolReaches) {
  Reach reach(model(), model::EndEffectorKind::kSpraying);
  const AreaMap& m = areas_of(reach, Task::kSpray, 0.3);
  const WallFrame wall = wall_of(reach, m);
  print(m, GetParam() == 0 ? "public" : "project");
  ASSERT_EQ(m.areas.size(), 4u);
  EXPECT_EQ(m.areas[3].id, "all");
  EXPECT_EQ(m.areas[0].id, "left");
  EXPECT_EQ(m.areas[1].id, "centre");
  EXPECT_EQ(m.areas[2].id, "right");
  // A 2.15 m arm covers two adjacent 0.7 m wide areas without moving the base. Their height is
  // bounded by the continuous torques: the project database's (paper Table 1) allow 0.45 m at
  // 2.05-2.5 m; the public database gives peak torques only (no tighter continuous torque).
  EXPECT_GE(m.band.width(), 1.4);
  EXPECT_GE(m.band.height(), GetParam() == 0 ? 0.8 : 0.4);
  EXPECT_LT(m.band.height(), 3.0);  // bounded by the arm, not by the search
  for (std::size_t i = 0; i < m.areas.size(); ++i) {
    std::string why;
    EXPECT_TRUE(m.covers(m.areas[i].rect, &why)) << m.areas[i].id << ": " << why;
    if (i > 0 && i < 3) {
      EXPECT_NEAR(m.areas[i].rect.x0, m.areas[i - 1].rect.x1, 1e-9);
    }
    EXPECT_TRUE(m.band.contains(m.areas[i].rect));
  }
  // Just above the band the tool is out of reach (the band is the arm's, not the grid's).
  const Rect above{m.band.x0, m.band.x1, m.band.y1 + m.grid, m.band.y1 + m.grid};
  if (m.band.y1 + m.grid <= m.y_min + (m.ny - 1) * m.grid) {
    std::string why;
    EXPECT_FALSE(m.covers(above, &why));
    EXPECT_FALSE(why.empty());
  }
  // A point of the centre area, solved afresh from the neutral posture, puts the TCP there.
  const Area& c = m.area("centre");
  const Eigen::Isometry3d t = Reach::target(wall, 0.5 * (c.rect.x0 + c.rect.x1), 0.5 * (c.rect.y0 + c.rect.y1), 0.3, m.roll);
  const ReachPose p = reach.solve(t, wall, reach.neutral(), nullptr, true);
  ASSERT_TRUE(p.ok) << p.reason;
  EXPECT_LT((reach.tcp_pose(p.q).translation() - t.translation()).norm(), 2e-3);
  EXPECT_FALSE(reach.self_collision(p.q));
  EXPECT_THROW((void)m.area("ceiling"), FinishError);
}

INSTANTIATE_TEST_SUITE_P(BothDatabases, SprayingMorphologyB, ::testing::Values(0, 1),
                         [](const ::testing::TestParamInfo<int>& i) { return i.param == 0 ? std::string("Public") : std::string("Project"); });

TEST(Areas, SandingMorphologyHasAreasWithTheDiscOnTheWall) {
  auto m = test::model_of(test::source_dir() / "deploy/demo/sanding_robot.yaml", test::project_db());
  ReachParams rp;
  rp.contact_force = 30.0;  // the paper's sanding force
  Reach reach(m, model::EndEffectorKind::kSanding, rp);
  EXPECT_THROW(Reach(m, model::EndEffectorKind::kSpraying), FinishError);
  const AreaMap& a = areas_of(reach, Task::kSand, 0.0);
  print(a, "sanding");
  ASSERT_EQ(a.areas.size(), 4u);
  EXPECT_GE(a.band.height(), 0.3);
  EXPECT_GE(a.band.width(), 0.9);
}

TEST(Areas, ReshapedRectangleStaysInsideItsArea) {
  const Area area{"centre", Rect{-0.35, 0.35, 0.8, 2.0}};
  const Rect window_free{-0.35, 0.1, 1.2, 2.0};
  const Rect r = reshape(area, window_free);
  EXPECT_DOUBLE_EQ(r.x1, 0.1);
  EXPECT_TRUE(area.rect.contains(r));
  try {
    (void)reshape(area, Rect{-0.35, 0.5, 1.2, 2.0});
    FAIL() << "a rectangle sticking out of its area was accepted";
  } catch (const FinishError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not inside area 'centre'"));
  }
  EXPECT_THROW((void)reshape(area, Rect{0.1, 0.1, 1.2, 2.0}), FinishError);
}

TEST(Serpentine, StrokeCountFollowsWidthToolAndOverlap) {
  EXPECT_EQ(stroke_count(0.7, 0.1, 0.0), 7);  // the paper's 0.7 m areas, 0.1 m coats (Table 2)
  EXPECT_EQ(stroke_count(0.7, 0.1, 0.1), 8);
  EXPECT_EQ(stroke_count(0.7, 0.23, 0.1), 4);  // a 0.23 m sanding disc
  EXPECT_EQ(stroke_count(0.08, 0.1, 0.1), 1);
  EXPECT_EQ(stroke_count(0.1001, 0.1, 0.0), 2);
  EXPECT_THROW((void)stroke_count(0.7, 0.0, 0.1), FinishError);
  EXPECT_THROW((void)stroke_count(0.7, 0.1, 0.95), FinishError);
  double spacing = 0.0;
  const auto strokes = serpentine_strokes(Rect{0.0, 0.7, 1.0, 1.8}, spray_tool(0.0), 0.1, &spacing);
  ASSERT_EQ(strokes.size(), 7u);
  EXPECT_NEAR(spacing, 0.1, 1e-12);
  EXPECT_NEAR(strokes.front().x, 0.05, 1e-12);
  EXPECT_NEAR(strokes.back().x, 0.65, 1e-12);
  for (std::size_t i = 0; i < strokes.size(); ++i) EXPECT_EQ(strokes[i].up(), i % 2 == 0) << i;
}

TEST(Serpentine, AreaOutOfReachIsRefusedWithAReason) {
  Reach reach(spraying_project(), model::EndEffectorKind::kSpraying);
  const AreaMap& m = areas_of(reach, Task::kSpray, 0.3);
  const WallFrame wall = wall_of(reach, m);
  const Rect too_high{-0.35, 0.35, m.band.y1 + 0.5, m.band.y1 + 1.2};
  try {
    (void)plan_serpentine(reach, wall, too_high, spray_tool(), m.roll, PathParams{}, reach.neutral());
    FAIL() << "an area above the reach was planned";
  } catch (const FinishError& e) {
    EXPECT_THAT(e.what(), HasSubstr("path refused"));
    std::printf("refused: %s\n", e.what());
  }
  // Too fast for the joints: refused too, naming the joint.
  const Area& c = m.area("centre");
  PathParams fast;
  fast.speed = 5.0;
  fast.acceleration = 20.0;
  const Rect small{c.rect.x0, c.rect.x0 + 0.3, c.rect.y0, c.rect.y1};
  try {
    (void)plan_serpentine(reach, wall, small, spray_tool(), m.roll, fast, reach.neutral(),
                          &m.posture_near(small.x0, small.y0));
    FAIL() << "a path beyond the joints' speed was planned";
  } catch (const FinishError& e) {
    EXPECT_THAT(e.what(), HasSubstr("rad/s"));
  }
}

/// The demo's sanding robot at 30 N in front of its wall: what the sanding plans start from.
struct SandingRig {
  std::shared_ptr<const model::RobotModel> model =
      test::model_of(test::source_dir() / "deploy/demo/sanding_robot.yaml", test::project_db());
  Reach reach{model, model::EndEffectorKind::kSanding, [] {
                ReachParams rp;
                rp.contact_force = 30.0;
                return rp;
              }()};
  const AreaMap& m = areas_of(reach, Task::kSand, 0.0);
  const WallFrame wall = wall_of(reach, m);
};

// The sanding robot's joint move from its start posture ends 0.1 m off the wall
// (PathParams::move_standoff), then a straight line leads to the approach pose 5 cm off: every
// area plans, left and `all` included, and the move keeps the 5 cm it is checked for. With the
// move ending at the approach pose itself (move_standoff 0, as before) the left area is refused:
// the move swings the disc under 5 cm on its way there.
TEST(Serpentine, SandingMoveEndsOffTheWallSoEveryAreaPlans) {
  SandingRig rig;
  const auto& model = rig.model;
  Reach& reach = rig.reach;
  const AreaMap& m = rig.m;
  const WallFrame& wall = rig.wall;
  print(m, "sanding");
  const ToolSpec disc{Task::kSand, 0.0, 0.23, 0.1};
  const PathParams sanding{0.1, 0.5, 0.02, 0.05, 0.05, 0.0, 0.0, 0.8};
  const Eigen::VectorXd start = Eigen::VectorXd::Zero(model->kinematics().dof());  // the simulator's start
  for (const Area& a : m.areas) {
    const auto strokes = serpentine_strokes(a.rect, disc, 0.0);
    SerpentinePlan plan;
    try {
      plan = plan_serpentine(reach, wall, a.rect, disc, m.roll, sanding, start,
                             &m.posture_near(strokes.front().x, strokes.front().y_start));
    } catch (const FinishError& e) {
      ADD_FAILURE() << a.id << ": " << e.what();
      continue;
    }
    // The joint move (before the first sample on the plan's line) stays 5 cm off, ends at 0.1 m;
    // the line then passes the approach pose 5 cm off and reaches the wall.
    double closest = 1e9;
    std::size_t i = 0;
    const Eigen::Vector3d p0 = Eigen::Vector3d(strokes.front().x, strokes.front().y_start, 0.1);
    for (; i < plan.samples.size() && (plan.samples[i].wall - p0).norm() > 1e-9; ++i) {
      closest = std::min(closest, wall.coordinates(reach.tcp_pose(plan.samples[i].q).translation()).z());
    }
    ASSERT_LT(i, plan.samples.size()) << a.id << ": no sample at the end of the joint move 0.1 m off";
    EXPECT_GE(closest, 0.05) << a.id;
    EXPECT_GT(i, 10u) << a.id;  // a joint move there was
    bool approach_pose = false, on_wall = false;
    for (std::size_t k = i; k < plan.samples.size(); ++k) {
      approach_pose = approach_pose || std::abs(plan.samples[k].wall.z() - 0.05) < 1e-6;
      on_wall = on_wall || plan.samples[k].stroke == 0;
      if (k > i) {
        EXPECT_LE((plan.samples[k].wall - plan.samples[k - 1].wall).norm(), 0.01) << a.id << " at " << k;
      }
    }
    EXPECT_TRUE(approach_pose && on_wall) << a.id;
    std::printf("%s: %zu samples, the joint move %.1f s, at least %.0f mm off the wall\n", a.id.c_str(),
                plan.samples.size(), plan.samples[i].t, closest * 1e3);
  }
  PathParams old = sanding;
  old.move_standoff = 0.0;
  const Area& left = m.area("left");
  const auto strokes = serpentine_strokes(left.rect, disc, 0.0);
  try {
    (void)plan_serpentine(reach, wall, left.rect, disc, m.roll, old, start,
                          &m.posture_near(strokes.front().x, strokes.front().y_start));
    ADD_FAILURE() << "the move ending 5 cm off the wall was planned for the left area";
  } catch (const FinishError& e) {
    EXPECT_THAT(e.what(), HasSubstr("from the wall")) << e.what();
  }
}

// The wall clearance counts the arm's shapes, not its TCP: the disc (0.23 m, its face at the
// TCP) parallel to the wall keeps the TCP's distance; tilted by 15 degrees its rim comes
// 0.115 sin(15 deg) = 30 mm nearer, which the TCP alone does not show.
TEST(Reach, TheWallClearanceCountsATiltedDiscsRim) {
  SandingRig rig;
  Reach& reach = rig.reach;
  const Rect& centre = rig.m.area("centre").rect;
  const double x = 0.5 * (centre.x0 + centre.x1), y = 0.5 * (centre.y0 + centre.y1);
  const Eigen::Isometry3d flat = Reach::target(rig.wall, x, y, 0.1, rig.m.roll);
  const ReachPose a = reach.solve(flat, rig.wall, rig.m.posture_near(x, y), nullptr, true);
  ASSERT_TRUE(a.ok) << a.reason;
  std::string link;
  const double parallel = reach.wall_clearance(a.q, rig.wall, &link);
  EXPECT_NEAR(parallel, 0.1, 1e-3) << link;
  EXPECT_FALSE(link.empty());
  Eigen::Isometry3d tilted = flat;
  tilted.rotate(Eigen::AngleAxisd(15.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()));
  const ReachPose b = reach.solve(tilted, rig.wall, a.q, nullptr, true);
  ASSERT_TRUE(b.ok) << b.reason;
  EXPECT_NEAR(rig.wall.coordinates(reach.tcp_pose(b.q).translation()).z(), 0.1, 1e-3);  // the TCP as far
  EXPECT_NEAR(reach.wall_clearance(b.q, rig.wall), 0.1 - 0.115 * std::sin(15.0 * M_PI / 180.0), 1.5e-3);
}

// A new model version with the same arm and tool puts the disc where the old one did at the
// joints measured now: a run in contact leaves the wall under it (leave_for_new_model). Another
// arm and tool (the spraying robot), a model that did not build, or no joints measured yet:
// the run stops where it is and the arm holds.
TEST(SandSequence, ANewModelWithTheSameArmLeavesTheWallAnotherArmHolds) {
  SandingRig rig;
  const auto again = test::model_of(test::source_dir() / "deploy/demo/sanding_robot.yaml", test::project_db());
  const auto spraying = spraying_project();
  const kinematics::Model& k = rig.model->kinematics();
  const Rect& centre = rig.m.area("centre").rect;
  const auto strokes = serpentine_strokes(centre, ToolSpec{Task::kSand, 0.0, 0.23, 0.1}, 0.0);
  const SerpentinePlan plan = plan_serpentine(rig.reach, rig.wall, centre, ToolSpec{Task::kSand, 0.0, 0.23, 0.1},
                                              rig.m.roll, PathParams{0.1, 0.5, 0.02, 0.05, 0.05, 0.0, 0.0, 0.8},
                                              Eigen::VectorXd::Zero(k.dof()),
                                              &rig.m.posture_near(strokes.front().x, strokes.front().y_start));
  const Eigen::VectorXd& q = plan.samples[plan.samples.size() / 2].q;  // in contact, mid-run
  const auto in_contact = [&]() {
    auto seq = std::make_unique<SandSequence>(plan, SandParams{});
    seq->start(0.0);
    (void)seq->update(0.2);
    return seq;
  };
  NewModel n;
  n.version = 9;
  n.before = rig.model.get();
  n.tcp_frame = rig.reach.tcp_frame();
  n.names = k.joint_names();
  n.positions.assign(q.data(), q.data() + q.size());

  n.after = again.get();
  auto same = in_contact();
  ASSERT_EQ(same->phase(), SandPhase::kApproach);
  EXPECT_TRUE(leave_for_new_model(*same, n));
  EXPECT_EQ(same->phase(), SandPhase::kLeaving);
  EXPECT_EQ(same->reason(), "the robot model changed to version 9");

  n.after = spraying.get();
  auto other = in_contact();
  EXPECT_FALSE(leave_for_new_model(*other, n));
  EXPECT_EQ(other->phase(), SandPhase::kAborted);
  EXPECT_EQ(other->reason(),
            "the robot model changed to version 9; the new model's arm is another: the arm holds where it is");

  n.after = nullptr;
  n.error = "URDF: no root link";
  auto broken = in_contact();
  EXPECT_FALSE(leave_for_new_model(*broken, n));
  EXPECT_EQ(broken->reason(), "the robot model changed to version 9 (URDF: no root link): the arm holds where it is");

  n.after = again.get();
  n.names.clear();
  n.positions.clear();
  auto unmeasured = in_contact();
  EXPECT_FALSE(leave_for_new_model(*unmeasured, n));
  EXPECT_EQ(unmeasured->phase(), SandPhase::kAborted);
}

// A run ends backed off the wall by the approach (5 cm); the next run starts there, a hair nearer
// with the arm's tracking error. Its move from there is planned: it goes no nearer than where it
// starts (the sand system test's second run was refused so, now and then).
TEST(Serpentine, TheNextRunStartsWhereTheLastEndedJustUnderTheApproach) {
  SandingRig rig;
  const auto& model = rig.model;
  Reach& reach = rig.reach;
  const AreaMap& m = rig.m;
  const WallFrame& wall = rig.wall;
  const ToolSpec disc{Task::kSand, 0.0, 0.23, 0.1};
  const PathParams sanding{0.1, 0.5, 0.02, 0.05, 0.05, 0.0, 0.0, 0.8};
  const Area& centre = m.area("centre");
  const auto strokes = serpentine_strokes(centre.rect, disc, 0.0);
  const SerpentinePlan first =
      plan_serpentine(reach, wall, centre.rect, disc, m.roll, sanding,
                      Eigen::VectorXd::Zero(model->kinematics().dof()),
                      &m.posture_near(strokes.front().x, strokes.front().y_start));
  // Where the first run ends, 1.5 mm nearer the wall.
  const Eigen::Vector3d end = first.samples.back().wall;
  ASSERT_NEAR(end.z(), 0.05, 1e-6);
  const ReachPose under =
      reach.solve(Reach::target(wall, end.x(), end.y(), end.z() - 0.0015, m.roll), wall, first.samples.back().q);
  ASSERT_TRUE(under.ok) << under.reason;
  SerpentinePlan second;
  try {
    second = plan_serpentine(reach, wall, centre.rect, disc, m.roll, sanding, under.q,
                             &m.posture_near(strokes.front().x, strokes.front().y_start));
  } catch (const FinishError& e) {
    FAIL() << "the next run from where the last ended was refused: " << e.what();
  }
  EXPECT_FALSE(second.samples.empty());
}

// The planned path fed to the deposition model (TCP poses interpolated at 2 ms).
SprayDeposition deposit(const SerpentinePlan& plan, const WallFrame& wall, double extra_standoff = 0.0) {
  SprayDeposition dep(wall, plan.rect, plan.tool, plan.params.speed, static_cast<int>(plan.strokes.size()));
  const Eigen::Vector3d shift = extra_standoff * wall.pose.linear().col(2);
  for (std::size_t i = 1; i < plan.samples.size(); ++i) {
    const PathSample& a = plan.samples[i - 1];
    const PathSample& b = plan.samples[i];
    if (!b.tool_on || b.stroke != a.stroke) continue;
    const int sub = std::max(1, static_cast<int>(std::ceil((b.t - a.t) / 0.002)));
    for (int k = 0; k < sub; ++k) {
      Eigen::Isometry3d t = b.tcp;
      t.translation() = a.tcp.translation() + (b.tcp.translation() - a.tcp.translation()) * ((k + 0.5) / sub) + shift;
      if (valve_open(plan.strokes[static_cast<std::size_t>(b.stroke)], wall.coordinates(t.translation()))) {
        dep.add(t, (b.t - a.t) / sub, b.stroke);
      }
    }
  }
  return dep;
}

// The measured postures are followed along the plan by the arm's joints alone: after nav drove
// the base, the wheels stand at tens of radians and the steering elsewhere than in the plan's
// seed postures. Every measured posture of the executed plan is tracked to its own sample, and
// the strokes (tool on) are reached; over all joints the tracker stayed at the first sample and
// a spray run in a shift painted nothing (0 % coverage).
TEST(Serpentine, TheMeasuredPostureIsTrackedByTheArmsJointsWhereverTheBaseWasDriven) {
  Reach reach(spraying_project(), model::EndEffectorKind::kSpraying);
  const AreaMap& m = areas_of(reach, Task::kSpray, 0.3);
  const WallFrame wall = wall_of(reach, m);
  const Area& c = m.area("centre");
  const auto first = serpentine_strokes(c.rect, spray_tool()).front();
  Eigen::VectorXd driven = reach.neutral();
  std::vector<bool> is_arm(static_cast<std::size_t>(driven.size()), false);
  for (const int j : reach.arm_joints()) is_arm[static_cast<std::size_t>(j)] = true;
  for (Eigen::Index j = 0; j < driven.size(); ++j) {
    if (!is_arm[static_cast<std::size_t>(j)]) driven[j] = 40.0 + 0.5 * static_cast<double>(j);  // legs: where nav left them
  }
  const SerpentinePlan plan = plan_serpentine(reach, wall, c.rect, spray_tool(), m.roll, PathParams{}, driven,
                                              &m.posture_near(first.x, first.y_start));
  std::size_t at = 0, on = 0;
  for (std::size_t i = 0; i < plan.samples.size(); ++i) {
    Eigen::VectorXd measured = driven;  // the legs hold; the arm is at sample i
    for (const int j : reach.arm_joints()) measured[j] = plan.samples[i].q[j];
    at = track_sample(plan, reach.arm_joints(), at, measured);
    // At sample i, or at an earlier one with the same arm posture (a stroke's end held).
    double off = 0.0;
    for (const int j : reach.arm_joints()) off += std::abs(plan.samples[at].q[j] - measured[j]);
    EXPECT_LE(at, i);
    EXPECT_LT(off, 1e-12) << "sample " << i << " tracked to " << at;
    on += plan.samples[at].tool_on ? 1 : 0;
  }
  EXPECT_GT(on, plan.samples.size() / 3);
  // Over every joint, as before: the plan's later samples have the legs where the seed postures
  // have them, so the measured legs hold the tracker back before the strokes.
  std::vector<int> every(static_cast<std::size_t>(driven.size()));
  for (std::size_t j = 0; j < every.size(); ++j) every[j] = static_cast<int>(j);
  std::size_t stuck = 0;
  for (std::size_t i = 0; i < plan.samples.size(); ++i) {
    Eigen::VectorXd measured = driven;
    for (const int j : reach.arm_joints()) measured[j] = plan.samples[i].q[j];
    stuck = track_sample(plan, every, stuck, measured);
  }
  std::printf("tracked over every joint: sample %zu of %zu\n", stuck, plan.samples.size());
  EXPECT_LT(stuck, plan.samples.size() / 2);
}

TEST(Deposition, PlannedPathCoversTheRectangleWithCoatsOfTheToolsWidth) {
  Reach reach(spraying_project(), model::EndEffectorKind::kSpraying);
  const AreaMap& m = areas_of(reach, Task::kSpray, 0.3);
  const WallFrame wall = wall_of(reach, m);
  const Area& c = m.area("all");
  const Rect rect = reshape(c, Rect{c.rect.x0, c.rect.x0 + 0.7, c.rect.y0, c.rect.y1});
  const auto first = serpentine_strokes(rect, spray_tool()).front();
  const SerpentinePlan plan = plan_serpentine(reach, wall, rect, spray_tool(), m.roll, PathParams{}, reach.neutral(),
                                              &m.posture_near(first.x, first.y_start));
  ASSERT_EQ(plan.strokes.size(), 8u);
  // The TCP follows the targets: the joints reach every sample (checked by the planner) and FK agrees.
  for (std::size_t i = 0; i < plan.samples.size(); i += 17) {
    EXPECT_LT((reach.tcp_pose(plan.samples[i].q).translation() - plan.samples[i].tcp.translation()).norm(), 2e-3) << i;
  }
  std::vector<double> xs;
  std::vector<bool> ups;
  for (const Stroke& s : plan.strokes) {
    xs.push_back(s.x);
    ups.push_back(s.up());
  }
  const SprayDeposition dep = deposit(plan, wall);
  const SprayReport rep = dep.measure(xs, ups);
  std::printf("%s\n", SprayDeposition::to_json(rep).c_str());
  EXPECT_GE(rep.coverage, 0.99);
  EXPECT_GT(rep.overspray_area, 0.0);
  EXPECT_LT(rep.overspray_area, 0.1);
  ASSERT_EQ(rep.coats.size(), 8u);
  for (const CoatMeasure& coat : rep.coats) {
    EXPECT_NEAR(coat.width, 0.1, 0.005) << coat.x;
    EXPECT_LT(coat.bottom, rect.y0 + 0.002);
    EXPECT_GT(coat.top, rect.y1 - 0.002);
  }
  EXPECT_LE(rep.max_abs_delta_h, 0.005);
  const fs::path dir = fs::temp_directory_path() / ("surface_finish_core_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  dep.write_png((dir / "coverage.png").string());
  EXPECT_GT(fs::file_size(dir / "coverage.png"), 1000u);
  const auto json = nlohmann::json::parse(SprayDeposition::to_json(rep));
  EXPECT_EQ(json["coats"].size(), 8u);
  EXPECT_NEAR(json["coats"][0]["width_mm"].get<double>(), 100.0, 5.0);
  fs::remove_all(dir);

  // The same path 3 cm further off the wall paints wider coats: the measure sees it.
  const SprayReport far = deposit(plan, wall, 0.03).measure(xs, ups);
  for (const CoatMeasure& coat : far.coats) EXPECT_NEAR(coat.width, 0.11, 0.004) << coat.x;
  EXPECT_GT(far.max_width_error, 0.005);
}

TEST(Deposition, GapBetweenStrokesLowersTheCoverage) {
  const WallFrame wall = WallFrame::ahead(1.8, 0.5);
  const Rect rect{0.0, 0.3, 1.0, 1.5};
  SprayDeposition dep(wall, rect, spray_tool(), 0.2, 2);
  // Two strokes 0.2 m apart with 0.1 m coats: a 0.1 m gap between them.
  for (int s = 0; s < 2; ++s) {
    for (double y = 0.9; y <= 1.6; y += 0.001) {
      dep.add(Reach::target(wall, 0.05 + 0.2 * s, y, 0.3, 0.0), 0.001 / 0.2, s);
    }
  }
  const SprayReport rep = dep.measure({0.05, 0.25}, {true, true});
  EXPECT_NEAR(rep.coverage, 2.0 / 3.0, 0.02);
  EXPECT_NEAR(rep.coats[0].width, 0.1, 0.003);
  EXPECT_THROW((void)dep.measure({0.05}, {true}), FinishError);
  EXPECT_THROW(SprayDeposition(wall, Rect{0, 0, 0, 1}, spray_tool(), 0.2, 1), FinishError);
}

}  // namespace
}  // namespace concert::surface_finish

namespace concert::surface_finish {
namespace {

TEST(WallFit, FindsTheWallAheadAmongClutter) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<Eigen::Vector2d> pts;
  // A wall 1.9 m ahead turned 5 degrees, a side wall, and a post.
  const double yaw = 5.0 * M_PI / 180.0;
  for (double s = -1.5; s <= 1.5; s += 0.01) {
    pts.emplace_back(Eigen::Vector2d(1.9, 0.0) + Eigen::Vector2d(-std::sin(yaw), std::cos(yaw)) * s +
                     Eigen::Vector2d(noise(rng), noise(rng)));
  }
  for (double x = 0.0; x <= 1.8; x += 0.02) pts.emplace_back(x, -1.2);
  for (int i = 0; i < 30; ++i) pts.emplace_back(1.0 + noise(rng), 0.3 + noise(rng));
  pts.emplace_back(std::nan(""), 0.0);
  const WallFit fit = fit_wall(pts, 0.9);
  EXPECT_NEAR(fit.wall.distance(), 1.9 * std::cos(yaw), 0.01);
  const Eigen::Vector3d n = fit.wall.pose.linear().col(2);
  EXPECT_NEAR(std::atan2(-n.y(), -n.x()), yaw, 0.01);
  EXPECT_NEAR(fit.wall.pose.translation().z(), -0.9, 1e-12);
  EXPECT_LT(fit.rms, 0.01);
  EXPECT_THROW((void)fit_wall({Eigen::Vector2d(-1, 0), Eigen::Vector2d(1, 3)}, 0.9), FinishError);
}

}  // namespace
}  // namespace concert::surface_finish

namespace concert::surface_finish {
namespace {

// The admittance law on a one-dimensional contact: the impedance (2000 N/m) pulls the tool to
// its reference, the wall (a 50 kN/m plaster layer with 3 mm bumps and holes passing under the
// disc at 0.1 m/s) pushes back; the tool's own dynamics are left out (quasi-static).
TEST(Admittance, HoldsThirtyNewtonsOverBumpsAndHoles) {
  const double k_imp = 2000.0, k_wall = 50000.0, dt = 0.001;
  ForceAdmittance law(30.0);
  std::vector<ForceSample> trace;
  const double contact0 = 0.0;  // the reference starts touching the nominal surface
  double force = 0.0;
  for (double t = 0.0; t < 14.0; t += dt) {
    const double s = t > 4.0 ? 0.1 * (t - 4.0) : 0.0;  // the stroke starts after the ramp and a wait
    // Surface height along the stroke: bumps (+) and holes (-) of 3 mm, cosine profiles 0.1 m wide.
    const double phase = std::fmod(s, 0.4);
    const double bump = phase < 0.1 ? 0.0015 * (1 - std::cos(2 * M_PI * phase / 0.1)) : 0.0;
    const double hole = (phase > 0.2 && phase < 0.3) ? -0.0015 * (1 - std::cos(2 * M_PI * (phase - 0.2) / 0.1)) : 0.0;
    const double surface = contact0 - bump - hole;  // z into the wall: a bump comes towards the tool
    const double ref = law.update(force, dt);
    // Quasi-static contact of two springs in series.
    const double x = ref > surface ? (k_imp * ref + k_wall * surface) / (k_imp + k_wall) : ref;
    force = x > surface ? k_wall * (x - surface) : 0.0;
    trace.push_back({t, force, force, t > 4.0});
  }
  const ForceStats st = force_stats(trace, 30.0, 3.0);
  std::printf("mean %.2f N, [%.2f, %.2f] N, within +-3 N %.1f %%, outside %.2f s\n", st.mean, st.min, st.max,
              st.within_fraction * 100, st.time_outside);
  EXPECT_NEAR(st.mean, 30.0, 0.5);
  EXPECT_GE(st.within_fraction, 0.95);
  EXPECT_NEAR(law.setpoint(), 30.0, 1e-9);
  EXPECT_GT(law.offset(), 0.0);  // the reference went into the wall to press

  // Without the law (the reference frozen where the ramp ended) the bumps take the force far out.
  std::vector<ForceSample> open;
  for (double t = 0.0; t < 10.0; t += dt) {
    const double phase = std::fmod(0.1 * t, 0.4);
    const double bump = phase < 0.1 ? 0.0015 * (1 - std::cos(2 * M_PI * phase / 0.1)) : 0.0;
    const double ref = 30.0 / k_imp + 30.0 / k_wall;
    const double x = (k_imp * ref + k_wall * -bump) / (k_imp + k_wall);
    open.push_back({t, k_wall * (x + bump), std::nan(""), true});
  }
  EXPECT_LT(force_stats(open, 30.0, 3.0).within_fraction, 0.95);

  const std::string png = (std::filesystem::temp_directory_path() / ("admittance_" + std::to_string(::getpid()) + ".png")).string();
  write_force_png(trace, 30.0, 3.0, png);
  EXPECT_GT(std::filesystem::file_size(png), 1000u);
  std::filesystem::remove(png);
  EXPECT_THROW(ForceAdmittance(-1.0), FinishError);
  EXPECT_THROW((void)force_stats({}, 30.0, 3.0), FinishError);
}

}  // namespace
}  // namespace concert::surface_finish
