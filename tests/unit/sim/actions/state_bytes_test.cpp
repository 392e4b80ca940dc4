// What the robot learnt about the boxes (Memory) crosses to another process
// and back unchanged.
#include "plr/actions/state_bytes.hpp"

#include <gtest/gtest.h>

namespace plr::actions {
namespace {

TEST(MemoryBytes, AGivenUpBoxKeepsItsHistoryAndNeighbours) {
  Memory m;
  GripHistory& h = m.grips[7];
  h.failures = 3;
  h.drops = 1;
  h.cups = 12;
  h.given_up = true;
  h.last = "not pulled out";
  h.why = "3 grips failed";
  h.neighbours = {5, 6, 9};
  m.ungripped = {4};
  m.unreached[8] = "approach not planned";
  m.shaken = {2};
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(build(fbb, m));
  const auto* message = flatbuffers::GetRoot<msg::ActionMemory>(fbb.GetBufferPointer());
  const auto back = from_message(*message, "test");
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->grips.size(), 1u);
  const GripHistory& g = back->grips.at(7);
  EXPECT_EQ(g.failures, 3);
  EXPECT_EQ(g.drops, 1);
  EXPECT_EQ(g.cups, 12);
  EXPECT_TRUE(g.given_up);
  EXPECT_EQ(g.last, h.last);
  EXPECT_EQ(g.why, h.why);
  EXPECT_EQ(g.neighbours, h.neighbours);
  EXPECT_EQ(back->ungripped, m.ungripped);
  EXPECT_EQ(back->unreached, m.unreached);
  EXPECT_EQ(back->shaken, m.shaken);
}

}  // namespace
}  // namespace plr::actions
