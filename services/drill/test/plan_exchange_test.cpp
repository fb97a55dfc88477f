// The planner's answers as the drill keeps them (drill/plan_exchange.hpp).
#include "drill/plan_exchange.hpp"

#include <gtest/gtest.h>

namespace concert::drill {
namespace {

PlanReply reply(std::uint32_t id, PlanState state, std::size_t samples = 0) {
  PlanReply r;
  r.request_id = id;
  r.state = state;
  if (samples > 0) r.path.names = {"base_x", "J1_E"};
  for (std::size_t i = 0; i < samples; ++i) r.path.samples.push_back({0.1 * static_cast<double>(i), {0.1, 0.2}, {}});
  return r;
}

// An executed plan's trajectory comes once, with PLANNED; the execution's updates and SUCCEEDED
// come without it. It is kept (the holes' postures are recorded from it).
TEST(PlanExchange, AnExecutedPlansTrajectoryOutlivesItsUpdates) {
  PlanReply kept;
  merge_reply(kept, reply(17, PlanState::kPlanned, 2));
  merge_reply(kept, reply(17, PlanState::kExecuting));
  merge_reply(kept, reply(17, PlanState::kSucceeded));
  EXPECT_EQ(kept.state, PlanState::kSucceeded);
  ASSERT_EQ(kept.path.samples.size(), 2u);
  EXPECT_EQ(kept.path.names.size(), 2u);
  // An answer with a trajectory of its own replaces the kept one.
  merge_reply(kept, reply(17, PlanState::kPlanned, 1));
  EXPECT_EQ(kept.path.samples.size(), 1u);
  EXPECT_EQ(kept.state, PlanState::kPlanned);
}

// A planner's acknowledgement (PLANNING) written after its answer is stale: the answer stays.
TEST(PlanExchange, AStaleAcknowledgementNeverReplacesAnAnswer) {
  PlanReply kept;
  merge_reply(kept, reply(5, PlanState::kPlanning));
  EXPECT_EQ(kept.state, PlanState::kPlanning);
  PlanReply failed = reply(5, PlanState::kFailed);
  failed.failure = PlanFailure::kUnreachable;
  failed.reason = "no posture";
  merge_reply(kept, failed);
  merge_reply(kept, reply(5, PlanState::kPlanning));
  EXPECT_EQ(kept.state, PlanState::kFailed);
  EXPECT_EQ(kept.failure, PlanFailure::kUnreachable);
  EXPECT_EQ(kept.reason, "no posture");
  // Another request's answers are never mixed in: a new id replaces everything.
  merge_reply(kept, reply(6, PlanState::kPlanning));
  EXPECT_EQ(kept.request_id, 6u);
  EXPECT_EQ(kept.state, PlanState::kPlanning);
}

}  // namespace
}  // namespace concert::drill
