#include "gui/allow_list.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace concert::gui {
namespace {

TEST(AllowList, SafetyTopicsAreCommandableMotionAndTheSimulatorsWorldAreNot) {
  EXPECT_NE(find_operator_command("concert/safety/estop"), nullptr);
  EXPECT_NE(find_operator_command("concert/safety/reset"), nullptr);
  EXPECT_NE(find_operator_command("concert/drill/mission"), nullptr);
  EXPECT_EQ(find_operator_command("concert/robot/joint_command"), nullptr);
  EXPECT_EQ(find_operator_command("concert/robot/trajectory_command"), nullptr);
  EXPECT_EQ(find_operator_command("concert/safety/state"), nullptr);
  // The simulator: a hot swap (an engineer's), never a new world.
  const auto swap = admit_command("concert/sim/command", Json{{"content", "a"}}, "1.2.3.4:5", 7);
  EXPECT_EQ(swap["kind"], "SIM_SWAP_ASSEMBLY");
  EXPECT_EQ(swap["source"], "concert gui (1.2.3.4:5)");
  EXPECT_THROW(admit_command("concert/sim/command", Json{{"kind", "SIM_SET_WORLD"}}, "o", 7), CommandRefused);
  EXPECT_EQ(find_operator_command("concert/sim/command")->role, Role::kEngineer);
}

TEST(AllowList, RolesDecideWhoMaySendWhatAndTheEStopIsEveryones) {
  for (Role r : {Role::kViewer, Role::kOperator, Role::kEngineer}) {
    EXPECT_NO_THROW(check_role("concert/safety/estop", r));
  }
  EXPECT_THROW(check_role("concert/safety/reset", Role::kViewer), CommandRefused);
  EXPECT_NO_THROW(check_role("concert/safety/reset", Role::kOperator));
  EXPECT_NO_THROW(check_role("concert/collab/command", Role::kOperator));
  EXPECT_THROW(check_role("concert/model/customisation", Role::kOperator), CommandRefused);
  EXPECT_NO_THROW(check_role("concert/model/customisation", Role::kEngineer));
  try {
    check_role("concert/sim/command", Role::kOperator);
    FAIL();
  } catch (const CommandRefused& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("role operator may not command 'concert/sim/command'"));
    EXPECT_THAT(e.what(), testing::HasSubstr("needs engineer"));
  }
}

TEST(AllowList, RefusesTopicsOffTheListNamingThem) {
  try {
    admit_command("concert/robot/base_velocity", Json::object(), "1.2.3.4:5", 7);
    FAIL() << "no refusal";
  } catch (const CommandRefused& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("concert/robot/base_velocity"));
    EXPECT_THAT(e.what(), testing::HasSubstr("not an operator command"));
  }
  EXPECT_THROW(admit_command("concert/safety/estop", Json::array(), "o", 7), CommandRefused);
}

TEST(AllowList, EStopSourceIsAlwaysTheSoftwareStopAndStamped) {
  const Json in = {{"source", "ESTOP_WIRELESS"}, {"engaged", true}};
  const Json out = admit_command("concert/safety/estop", in, "10.0.0.5:4000", 1234);
  EXPECT_EQ(out["source"], "ESTOP_SOFTWARE");
  EXPECT_EQ(out["engaged"], true);
  EXPECT_EQ(out["stamp_ns"], 1234);
}

TEST(AllowList, ResetNamesTheClientAndKeepsAGivenStamp) {
  const Json out =
      admit_command("concert/safety/reset", {{"source", "me"}, {"stamp_ns", 99}}, "10.0.0.5:4000", 1234);
  EXPECT_EQ(out["source"], "concert gui (10.0.0.5:4000)");
  EXPECT_EQ(out["stamp_ns"], 99);
}

TEST(AllowList, FinishCommandsNameTheClientAndKeepTheOperatorsChoice) {
  const Json in = {{"source", "surface_finish"}, {"verb", "FINISH_SAND"}, {"area", "centre"}, {"force", 30.0}};
  const Json out = admit_command("concert/finish/command", in, "10.0.0.5:4000", 1234);
  EXPECT_EQ(out["source"], "concert gui (10.0.0.5:4000)");  // a browser cannot pose as a service
  EXPECT_EQ(out["verb"], "FINISH_SAND");
  EXPECT_EQ(out["area"], "centre");
  EXPECT_EQ(out["force"], 30.0);
  EXPECT_EQ(out["stamp_ns"], 1234);
}

TEST(AllowList, TransportButtonsAreDirectFromTheGui) {
  const Json out = admit_command("concert/collab/command", {{"text", "follow-me"}, {"direct", false}}, "o", 5);
  EXPECT_EQ(out["source"], "gui");
  EXPECT_EQ(out["direct"], true);
  EXPECT_EQ(out["text"], "follow-me");
}

TEST(AllowList, EveryEntryHasFixedFieldsThatParse) {
  for (const auto& c : operator_commands()) {
    EXPECT_TRUE(Json::parse(c.fixed_json).is_object()) << c.topic;
    EXPECT_FALSE(c.what.empty()) << c.topic;
  }
}

}  // namespace
}  // namespace concert::gui
