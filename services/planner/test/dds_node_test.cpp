// The planner's DDS adapter over real Fast DDS: model in -> READY at the version; requests in ->
// results out (stale version refused, plan with trajectory, execution streaming position
// commands with progress); `concert plan drill` end to end. Every wait is bounded.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "concert/common/text.hpp"
#include "concert/dds/participant.hpp"
#include "dds/planner_node.hpp"
#include "model_message.hpp"
#include "planner/cli.hpp"
#include "planner/fixtures.hpp"

using namespace concert;
using namespace concert::planner;
using namespace std::chrono_literals;

namespace {

using planner::testing::model_message;

msg::PlanRequest request(uint32_t id, uint32_t version, double z, bool execute) {
  msg::PlanRequest r;
  r.request_id(id);
  r.model_version(version);
  r.source("test");
  r.execute(execute);
  r.goals().push_back(planner::dds::to_msg(fixtures::drilling_area(2.0, 0.0, z)));
  return r;
}

// Waits (bounded) for a result of `id` in one of the final states; returns the last seen.
std::optional<msg::PlanResult> wait_final(concert::dds::Reader<msg::PlanResult>& reader, uint32_t id,
                                          std::vector<msg::PlanResult>* seen = nullptr) {
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (std::chrono::steady_clock::now() < deadline) {
    auto r = reader.wait(200ms);
    if (!r || r->request_id() != id) continue;
    if (seen) seen->push_back(*r);
    if (r->state() == msg::PLAN_SUCCEEDED || r->state() == msg::PLAN_FAILED) return r;
  }
  return std::nullopt;
}

class PlannerNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Params params;
    params.seed = 3;
    planner_ = std::make_unique<Planner>(params);
    Environment env(params.octomap_resolution);
    World w;
    w.boxes.push_back(fixtures::wall_at(2.0));
    env.add_world(w);
    planner_->set_environment(env);
    participant_ = std::make_unique<concert::dds::Participant>(concert::dds::ParticipantOptions{.name = "planner_test"});
    node_ = std::make_unique<planner::dds::PlannerNode>(*participant_, *planner_, planner::dds::NodeOptions{}, log_);
    spinner_ = std::thread([this] { node_->spin(stop_, 20ms); });
    models_ = std::make_unique<concert::dds::Writer<msg::RobotModel>>(*participant_, concert::dds::topics::robot_model);
    requests_ = std::make_unique<concert::dds::Writer<msg::PlanRequest>>(*participant_, concert::dds::topics::plan_request);
    results_ = std::make_unique<concert::dds::Reader<msg::PlanResult>>(*participant_, concert::dds::topics::plan_result);
  }
  void TearDown() override {
    stop_ = true;
    spinner_.join();
  }
  void publish_model(char which, uint32_t version) {
    models_->write(model_message(fixtures::data_dir() / (std::string("morphology_") + which + ".yaml"), static_cast<uint32_t>(version)));
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (node_->model_version() != version && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(10ms);
    ASSERT_EQ(node_->model_version(), version) << log_.str();
  }

  std::ostringstream log_;
  std::unique_ptr<Planner> planner_;
  std::unique_ptr<concert::dds::Participant> participant_;
  std::unique_ptr<planner::dds::PlannerNode> node_;
  std::atomic<bool> stop_{false};
  std::thread spinner_;
  std::unique_ptr<concert::dds::Writer<msg::RobotModel>> models_;
  std::unique_ptr<concert::dds::Writer<msg::PlanRequest>> requests_;
  std::unique_ptr<concert::dds::Reader<msg::PlanResult>> results_;
};

}  // namespace

TEST_F(PlannerNodeTest, ReadyAtModelVersionAndStatusReported) {
  concert::dds::Reader<msg::ServiceStatus> status(*participant_, concert::dds::topics::status);
  publish_model('a', 3);
  bool ready = false;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!ready && std::chrono::steady_clock::now() < deadline) {
    const auto s = status.wait(200ms);
    ready = s && s->service() == "planner" && s->state() == msg::SERVICE_READY && s->model_version() == 3;
  }
  EXPECT_TRUE(ready);
  // A broken model keeps version 3.
  msg::RobotModel bad;
  bad.version(4);
  bad.urdf("<robot name='x'/>");
  models_->write(bad);
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(node_->model_version(), 3u);
  EXPECT_NE(log_.str().find("version 4 refused"), std::string::npos) << log_.str();
}

TEST_F(PlannerNodeTest, StaleVersionIsRefusedAndPlansCarryTheTrajectory) {
  publish_model('a', 5);
  ASSERT_TRUE(requests_->wait_for_readers(1, 5s));
  requests_->write(request(11, 4, 2.2, false));
  const auto stale = wait_final(*results_, 11);
  ASSERT_TRUE(stale.has_value());
  EXPECT_EQ(stale->state(), msg::PLAN_FAILED);
  EXPECT_EQ(stale->failure(), msg::PLAN_STALE_MODEL);
  EXPECT_NE(stale->reason().find("version 4"), std::string::npos) << stale->reason();

  std::vector<msg::PlanResult> seen;
  requests_->write(request(12, 5, 2.2, false));
  const auto ok = wait_final(*results_, 12, &seen);
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(ok->state(), msg::PLAN_SUCCEEDED) << ok->reason();
  bool planned = false;
  // Latched, keep-last 1 per request: PLANNED may be superseded by SUCCEEDED before it is
  // read; both carry the trajectory of a planning-only request.
  for (const msg::PlanResult& r : seen) {
    if (r.state() != msg::PLAN_PLANNED && r.state() != msg::PLAN_SUCCEEDED) continue;
    planned = true;
    ASSERT_EQ(r.joint_names().size(), 9u);
    EXPECT_EQ(r.joint_names()[0], "base_x");
    ASSERT_GT(r.trajectory().size(), 2u);
    EXPECT_EQ(r.trajectory().back().position().size(), 9u);
  }
  EXPECT_TRUE(planned) << "no update with the trajectory";
}

TEST_F(PlannerNodeTest, ExecutionStreamsPositionCommandsWithProgress) {
  publish_model('a', 6);
  concert::dds::Reader<msg::JointCommand> commands(*participant_, concert::dds::topics::joint_command);
  concert::dds::Writer<msg::JointState> joint_state(*participant_, concert::dds::topics::joint_state);
  // Without a joint state the request cannot be executed.
  ASSERT_TRUE(requests_->wait_for_readers(1, 5s));
  requests_->write(request(21, 6, 2.3, true));
  const auto no_state = wait_final(*results_, 21);
  ASSERT_TRUE(no_state.has_value());
  EXPECT_EQ(no_state->failure(), msg::PLAN_INVALID_START);

  const auto model = planner_->model();
  msg::JointState js;
  js.model_version(6);
  for (int i = 3; i < model->full_dof(); ++i) {
    js.name().push_back(model->kinematics().joint_names()[static_cast<std::size_t>(i)]);
    js.position().push_back(0.0);
  }
  joint_state.write(js);
  std::this_thread::sleep_for(200ms);
  std::vector<msg::PlanResult> seen;
  requests_->write(request(22, 6, 2.3, true));
  const auto done = wait_final(*results_, 22, &seen);
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->state(), msg::PLAN_SUCCEEDED) << done->reason();
  EXPECT_DOUBLE_EQ(done->progress(), 1.0);
  const auto cmd = commands.wait(1s);
  ASSERT_TRUE(cmd.has_value());
  EXPECT_EQ(cmd->mode(), msg::JOINT_POSITION);
  EXPECT_EQ(cmd->model_version(), 6u);
  EXPECT_EQ(cmd->name().size(), 6u);
  EXPECT_EQ(cmd->position().size(), 6u);
}

TEST_F(PlannerNodeTest, CliSendsAGoalAndFollowsIt) {
  publish_model('b', 8);
  std::ostringstream out;
  std::ostringstream err;
  const auto plan = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "plan");
    return cli::run("concert", {register_verbs}, args, out, err);
  };
  EXPECT_EQ(plan({"drill"}), 2);
  EXPECT_NE(err.str().find("--at is required"), std::string::npos) << err.str();
  err.str("");
  EXPECT_EQ(plan({"drill", "--at", "2", "x", "1"}), 2);
  EXPECT_NE(err.str().find("--at: 'x' is not a number"), std::string::npos) << err.str();
  err.str("");
  out.str("");
  EXPECT_EQ(plan({"drill", "--at", "2.0", "0.1", "2.3", "--request-id", "31", "--timeout", "20"}),
            0)
      << err.str();
  EXPECT_NE(out.str().find("succeeded"), std::string::npos) << out.str();
  err.str("");
  out.str("");
  EXPECT_EQ(plan({"drill", "--at", "2.0", "0.1", "2.3", "--request-id", "33", "--timeout", "20",
                  "--json"}),
            0)
      << err.str();
  const auto lines = concert::split(out.str(), '\n');
  ASSERT_GE(lines.size(), 2u) << out.str();
  EXPECT_EQ(nlohmann::json::parse(lines.front()).at("request_id"), 33);
  EXPECT_EQ(nlohmann::json::parse(lines.back()).at("state"), "succeeded");
  err.str("");
  EXPECT_EQ(plan({"drill", "--at", "2.0", "0", "7.0", "--request-id", "32", "--timeout", "20"}), 1);
  EXPECT_NE(err.str().find("camera_E"), std::string::npos) << err.str();
}
