// Motions' outcomes as bus messages (sim/actions/motion_messages.cpp): what
// the simulator plug-in sends is what the executor's bus backend reads, the
// base's stall included, as the in-process backend sees it.
#include "plr/actions/motion_messages.hpp"

#include <gtest/gtest.h>

#include <plr/messages.hpp>

namespace plr::actions {
namespace {

Executed decoded(const flatbuffers::FlatBufferBuilder& fbb) {
  flatbuffers::Verifier verifier(fbb.GetBufferPointer(), fbb.GetSize());
  EXPECT_TRUE(verifier.VerifyBuffer<msg::ExecuteOutcome>());
  const auto e =
      decode_execute_outcome(*flatbuffers::GetRoot<msg::ExecuteOutcome>(fbb.GetBufferPointer()));
  EXPECT_TRUE(e) << e.error().message;
  return e ? *e : Executed{};
}

TEST(MotionMessages, AStalledBaseCrossesTheBus) {
  Executed e;
  e.unloaded = {4};
  e.unloaded_after_s = {1.5};
  e.sim_time_s = 12.0;
  e.stalled = true;
  e.stall_force = 2150.0;
  e.stall_after_s = 0.75;
  e.peak_push_force = 2150.0;
  flatbuffers::FlatBufferBuilder fbb;
  encode_execute_outcome(e, 17, fbb);
  const Executed back = decoded(fbb);
  EXPECT_EQ(back.unloaded, e.unloaded);
  EXPECT_EQ(back.sim_time_s, e.sim_time_s);
  EXPECT_TRUE(back.stalled);
  EXPECT_EQ(back.stall_force, e.stall_force);
  EXPECT_EQ(back.stall_after_s, e.stall_after_s);
  EXPECT_EQ(back.peak_push_force, e.peak_push_force);
}

// A simulator built before the fields existed: the base did not stall.
TEST(MotionMessages, AnOutcomeWithoutTheStallFieldsIsNoStall) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateExecuteOutcomeDirect(fbb, true, "", 3.0));
  const Executed back = decoded(fbb);
  EXPECT_FALSE(back.stalled);
  EXPECT_EQ(back.stall_force, 0.0);
  EXPECT_EQ(back.peak_push_force, 0.0);
  EXPECT_EQ(back.sim_time_s, 3.0);
}

}  // namespace
}  // namespace plr::actions
