// PlanRequest/PlanResponse conversion: the expansion budget and the stop
// reasons travel both ways.
#include <gtest/gtest.h>

#include <plr/messages.hpp>

#include "plr/sim/plan_types.hpp"

namespace plr::sim {
namespace {

flatbuffers::FlatBufferBuilder request(std::uint64_t budget) {
  msg::PlanRequestT req;
  req.mode = msg::PlanMode::M5;
  req.start = {1.0, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  req.goal_joints = {2.5, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  req.world = std::make_unique<msg::WorldStateT>();
  req.max_expansions = budget;
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::PlanRequest::Pack(fbb, &req));
  return fbb;
}

TEST(PlanMessages, ExpansionBudgetIsDecoded) {
  const auto fbb = request(1234);
  const auto d =
      decode_plan_request(*flatbuffers::GetRoot<msg::PlanRequest>(fbb.GetBufferPointer()));
  EXPECT_EQ(d.query.max_expansions, 1234u);
  const auto none = request(0);
  EXPECT_EQ(decode_plan_request(*flatbuffers::GetRoot<msg::PlanRequest>(none.GetBufferPointer()))
                .query.max_expansions,
            0u);
}

TEST(PlanMessages, StopReasonsAndEscapeTimeAreEncoded) {
  PlanResult r;
  r.status = PlanStatus::kTimeout;
  r.message = "no solution within the expansion budget of 3";
  r.stats.expansions = 3;
  r.stats.budget_exhausted = true;
  r.stats.escaped = true;
  r.stats.escape_time_s = 0.004;
  flatbuffers::FlatBufferBuilder fbb;
  encode_plan_response(r, "arastar", 0.02, fbb);
  const auto* m = flatbuffers::GetRoot<msg::PlanResponse>(fbb.GetBufferPointer());
  EXPECT_EQ(m->status(), msg::PlanStatus::Timeout);
  EXPECT_EQ(m->message()->str(), r.message);
  EXPECT_EQ(m->stats()->expansions(), 3u);
  EXPECT_TRUE(m->stats()->budget_exhausted());
  EXPECT_FALSE(m->stats()->time_limit_hit());
  EXPECT_TRUE(m->stats()->m6_used());
  EXPECT_DOUBLE_EQ(m->stats()->escape_ms(), 4.0);
}

}  // namespace
}  // namespace plr::sim
