// The sim.action kind's input and output bytes (plr/actions/simulation_job.hpp):
// a round trip, and untrusted bytes refused with the reason.
#include <gtest/gtest.h>

#include <plr/msg/generator_generated.h>

#include "plr/actions/simulation_job.hpp"

namespace plr::actions {
namespace {

// A TruckState buffer (what a rig's snapshot is); its contents do not matter here.
StateBytes truck_state(std::uint32_t unloaded) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateTruckState(fbb, 0, 0, unloaded));
  return std::make_shared<const std::vector<std::uint8_t>>(fbb.GetBufferPointer(),
                                                           fbb.GetBufferPointer() + fbb.GetSize());
}

TEST(SimulationJob, JobAndOutcomeRoundTrip) {
  const SimJob job{{truck_state(3), sim::Action::SweepMid}, R"({"h_pile":0.5})"};
  const auto back = decode_sim_job(encode_sim_job(job), "test");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(*back->request.state, *job.request.state);
  EXPECT_EQ(back->request.action, sim::Action::SweepMid);
  EXPECT_EQ(back->observation_json, job.observation_json);

  SimOutcome o;
  o.applicable = false;
  o.boxes = 4;
  o.robot_time_s = 12.5;
  o.observation = kEmptyObservation;
  o.boxes_left = 7;
  o.highest_stack_m = 1.25;
  o.wall_s = 0.5;
  o.state = truck_state(4);
  const auto out = decode_sim_outcome(encode_sim_outcome(o), "test");
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_EQ(out->applicable, o.applicable);
  EXPECT_EQ(out->boxes, o.boxes);
  EXPECT_EQ(out->robot_time_s, o.robot_time_s);
  EXPECT_EQ(out->observation, o.observation);
  EXPECT_EQ(out->boxes_left, o.boxes_left);
  EXPECT_EQ(out->highest_stack_m, o.highest_stack_m);
  EXPECT_EQ(out->wall_s, o.wall_s);
  EXPECT_EQ(*out->state, *o.state);
}

TEST(SimulationJob, UntrustedBytesAreRefused) {
  const jobs::Bytes garbage{1, 2, 3};
  EXPECT_EQ(decode_sim_job(garbage, "in").error().message, "in: not a SimJob");
  EXPECT_EQ(decode_sim_outcome(garbage, "out").error().message, "out: not a SimResult");

  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateSimJob(fbb, fbb.CreateVector(std::vector<std::uint8_t>{1, 2, 3, 4}),
                               sim::Action::SweepMid));
  const jobs::Bytes bad_state(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
  EXPECT_EQ(decode_sim_job(bad_state, "in").error().message, "in: job: state: not a TruckState");

  SimOutcome o;
  o.state = truck_state(0);
  o.observation = sim::kNumObservations;
  EXPECT_EQ(decode_sim_outcome(encode_sim_outcome(o), "out").error().message,
            "out: result: observation 18 out of range");
  o.observation = 0;
  o.robot_time_s = -1;
  EXPECT_EQ(decode_sim_outcome(encode_sim_outcome(o), "out").error().message,
            "out: result: robot_time_s must be finite and >= 0");
}

TEST(SimulationJob, TheWorkKeyNamesStateAndAction) {
  const auto s = truck_state(1);
  const std::uint64_t h = state_hash(*s);
  EXPECT_NE(work_key(h, sim::Action::SweepMid), work_key(h, sim::Action::SweepLow));
  EXPECT_NE(state_hash(*truck_state(2)), h);
}

// The fidelity travels with the job; a full job's bytes and key are what
// they were before the levels (stored results stay valid), the others'
// results are kept apart.
TEST(SimulationJob, TheFidelityTravelsWithTheJobAndNamesItsResult) {
  SimJob job{{truck_state(3), sim::Action::PickLowLeft}, "{}", sim::Fidelity::kFast};
  const auto back = decode_sim_job(encode_sim_job(job), "test");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->fidelity, sim::Fidelity::kFast);

  job.fidelity = sim::Fidelity::kFull;
  flatbuffers::FlatBufferBuilder fbb;
  const auto state = fbb.CreateVector(*job.request.state);
  const auto json = fbb.CreateString(job.observation_json);
  fbb.Finish(msg::CreateSimJob(fbb, state, job.request.action, json));
  EXPECT_EQ(encode_sim_job(job),
            jobs::Bytes(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()));

  const std::uint64_t h = state_hash(*job.request.state);
  const std::uint64_t before = [&] {  // the key as it was computed before fidelity levels
    std::uint64_t z =
        h ^ (static_cast<std::uint64_t>(sim::Action::SweepMid) + 1) * 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }();
  EXPECT_EQ(work_key(h, sim::Action::SweepMid), before);
  EXPECT_EQ(work_key(h, sim::Action::SweepMid, sim::Fidelity::kFull), before);
  EXPECT_NE(work_key(h, sim::Action::SweepMid, sim::Fidelity::kFast), before);
  EXPECT_NE(work_key(h, sim::Action::SweepMid, sim::Fidelity::kAdaptive),
            work_key(h, sim::Action::SweepMid, sim::Fidelity::kFast));

  flatbuffers::FlatBufferBuilder bad;
  bad.Finish(
      msg::CreateSimJob(bad, bad.CreateVector(*job.request.state), job.request.action, 0, 7));
  EXPECT_EQ(decode_sim_job(
                jobs::Bytes(bad.GetBufferPointer(), bad.GetBufferPointer() + bad.GetSize()), "in")
                .error()
                .message,
            "in: job: fidelity 7 out of range");
}

}  // namespace
}  // namespace plr::actions
