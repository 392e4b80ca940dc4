#include "rollout.hpp"

#include <plr/msg/chooser_data_generated.h>

#include <fmt/format.h>

#include <string>

#include "plr/episode/open_loop.hpp"
#include "plr/jobs/engine.hpp"
#include "plr/jobs/process_runner.hpp"

namespace plr::chooser {

namespace {

constexpr const char* kRolloutKind = "chooser.rollout";
// A few actions take seconds to minutes; a rollout past this is stuck.
constexpr double kRolloutTimeoutS = 3600;

jobs::Bytes encode(const Rollout& r) {
  flatbuffers::FlatBufferBuilder fbb(r.end.size() + 128);
  fbb.Finish(plr::msg::CreateChooserRollout(fbb, r.actions, r.boxes, r.robot_time_s,
                                            fbb.CreateVector(r.end)));
  return jobs::Bytes(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
}

plr::Expected<Rollout> decode(const jobs::Bytes& bytes) {
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  if (!verifier.VerifyBuffer<plr::msg::ChooserRollout>(nullptr))
    return plr::make_error(PLR_ERR_INTERNAL, "rollout: its result fails verification");
  const auto* r = flatbuffers::GetRoot<plr::msg::ChooserRollout>(bytes.data());
  Rollout out{r->actions(), r->boxes(), r->robot_time_s(), {}};
  if (r->end()) out.end.assign(r->end()->begin(), r->end()->end());
  return out;
}

}  // namespace

plr::Expected<Rollout> rollout(actions::Rig& rig, const std::vector<std::uint8_t>& state,
                               const RolloutJob& job, const sim::HardcodedParams& h,
                               std::uint64_t max_actions) {
  auto memory = rig.restore(state);
  if (!memory) return memory.error();
  if (!job.masses.empty())
    if (auto ok = rig.simulation().set_masses(job.masses); !ok) return ok.error();
  auto run =
      episode::run_open_loop(rig.model(), rig.backend(), *memory, job.strategy, h, max_actions);
  if (!run) return run.error();
  return Rollout{run->actions, run->boxes, run->robot_time_s, rig.snapshot(*memory)};
}

std::vector<plr::Expected<Rollout>> rollouts(actions::Rig& rig,
                                             const std::vector<std::uint8_t>& state,
                                             const std::vector<RolloutJob>& todo,
                                             const sim::HardcodedParams& h,
                                             std::uint64_t max_actions, int workers) {
  // The children inherit the state and the jobs: the input is the job's index.
  jobs::Kinds kinds;
  kinds.add(kRolloutKind, [&](const jobs::Bytes& input) -> plr::Expected<jobs::Bytes> {
    auto r = rollout(rig, state, todo.at(std::stoul(jobs::to_text(input))), h, max_actions);
    if (!r) return r.error();
    return encode(*r);
  });
  std::vector<jobs::Job> batch;
  for (std::size_t i = 0; i < todo.size(); ++i)
    batch.push_back({kRolloutKind, fmt::format("rollout{}", i), jobs::to_bytes(std::to_string(i))});
  std::vector<plr::Expected<Rollout>> results;
  auto runner = jobs::ProcessRunner::create(
      {{}, &kinds, static_cast<unsigned>(std::max(workers, 1)), kRolloutTimeoutS, 1, true, {}});
  if (!runner) {
    results.assign(todo.size(), runner.error());
    return results;
  }
  auto outcome = jobs::run(batch, **runner, nullptr);
  if (!outcome) {
    results.assign(todo.size(), outcome.error());
    return results;
  }
  for (const jobs::Result& r : outcome->results) {
    if (r.ok)
      results.push_back(decode(r.output));
    else
      results.push_back(plr::make_error(PLR_ERR_INVALID, r.error));
  }
  return results;
}

}  // namespace plr::chooser
