#include "drill/plan_exchange.hpp"

#include <utility>

namespace concert::drill {

void merge_reply(PlanReply& kept, const PlanReply& incoming) {
  const bool same = kept.request_id == incoming.request_id;
  if (same && incoming.state == PlanState::kPlanning && kept.state != PlanState::kPlanning) return;
  if (same && incoming.path.samples.empty() && !kept.path.samples.empty()) {
    Path path = std::move(kept.path);
    kept = incoming;
    kept.path = std::move(path);
    return;
  }
  kept = incoming;
}

}  // namespace concert::drill
