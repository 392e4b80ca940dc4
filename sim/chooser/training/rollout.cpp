#include "rollout.hpp"

#include <plr/msg/chooser_data_generated.h>

#include <fmt/format.h>

#include <string>

#include "plr/episode/open_loop.hpp"

namespace plr::chooser {

namespace {

jobs::Bytes finished(flatbuffers::FlatBufferBuilder& fbb) {
  return jobs::Bytes(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
}

jobs::Bytes encode(const Rollout& r) {
  flatbuffers::FlatBufferBuilder fbb(r.end.size() + 128);
  fbb.Finish(plr::msg::CreateChooserRollout(fbb, r.actions, r.boxes, r.robot_time_s,
                                            fbb.CreateVector(r.end)));
  return finished(fbb);
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

jobs::Bytes encode(const std::vector<std::uint8_t>& state, const RolloutJob& job) {
  std::vector<std::uint32_t> ids;
  std::vector<double> kg;
  for (const auto& [id, mass] : job.masses) {
    ids.push_back(id);
    kg.push_back(mass);
  }
  flatbuffers::FlatBufferBuilder fbb(state.size() + 16 * ids.size() + 128);
  fbb.Finish(plr::msg::CreateChooserRolloutJob(
      fbb, fbb.CreateVector(state), job.entry ? static_cast<std::int32_t>(*job.entry) : -1,
      fbb.CreateVector(ids), fbb.CreateVector(kg)));
  return finished(fbb);
}

// A job's input as it comes from a batch file or a parent process: checked
// against the library it will index.
plr::Expected<std::pair<std::vector<std::uint8_t>, RolloutJob>> decode_job(
    const jobs::Bytes& bytes, const sim::Library& library) {
  const auto bad = [](const std::string& what) {
    return plr::make_error(PLR_ERR_INVALID, "chooser.rollout job: " + what);
  };
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  if (!verifier.VerifyBuffer<plr::msg::ChooserRolloutJob>(nullptr))
    return bad("fails verification");
  const auto* j = flatbuffers::GetRoot<plr::msg::ChooserRolloutJob>(bytes.data());
  if (j->state() == nullptr) return bad("no state");
  RolloutJob job;
  if (j->entry() >= 0) {
    if (static_cast<std::size_t>(j->entry()) >= library.entries.size())
      return bad(fmt::format("entry {} of a library of {}", j->entry(), library.entries.size()));
    job.entry = static_cast<std::uint32_t>(j->entry());
  }
  const std::size_t n = j->mass_ids() ? j->mass_ids()->size() : 0;
  if (n != (j->masses() ? j->masses()->size() : 0)) return bad("mass ids and masses differ");
  for (std::size_t i = 0; i < n; ++i)
    job.masses.emplace_back(j->mass_ids()->Get(i), j->masses()->Get(i));
  return std::pair{std::vector<std::uint8_t>(j->state()->begin(), j->state()->end()),
                   std::move(job)};
}

}  // namespace

plr::Expected<Rollout> rollout(const RolloutContext& context,
                               const std::vector<std::uint8_t>& state, const RolloutJob& job) {
  actions::Rig& rig = context.rig;
  auto memory = rig.restore(state);
  if (!memory) return memory.error();
  if (!job.masses.empty())
    if (auto ok = rig.simulation().set_masses(job.masses); !ok) return ok.error();
  std::optional<sim::Strategy> strategy;
  if (job.entry) strategy = context.library.entries.at(*job.entry).strategy;
  auto run = episode::run_open_loop(rig.model(), rig.backend(), *memory, strategy, context.h,
                                    context.max_actions);
  if (!run) return run.error();
  return Rollout{run->actions, run->boxes, run->robot_time_s, rig.snapshot(*memory)};
}

plr::Expected<jobs::Bytes> run_rollout_job(const RolloutContext& context,
                                           const jobs::Bytes& input) {
  auto job = decode_job(input, context.library);
  if (!job) return job.error();
  auto r = rollout(context, job->first, job->second);
  if (!r) return r.error();
  return encode(*r);
}

void add_rollout_kind(jobs::Kinds& kinds, const RolloutContext& context) {
  kinds.add(kRolloutKind,
            [&context](const jobs::Bytes& input) { return run_rollout_job(context, input); });
}

std::vector<jobs::Job> rollout_jobs(const std::string& key, const std::vector<std::uint8_t>& state,
                                    const std::vector<RolloutJob>& todo) {
  std::vector<jobs::Job> out;
  for (std::size_t i = 0; i < todo.size(); ++i)
    out.push_back({kRolloutKind, fmt::format("{}-{}", key, i), encode(state, todo[i])});
  return out;
}

std::vector<plr::Expected<Rollout>> rollout_results(const jobs::Outcome& outcome) {
  std::vector<plr::Expected<Rollout>> results;
  for (const jobs::Result& r : outcome.results) {
    if (r.ok)
      results.push_back(decode(r.output));
    else
      results.push_back(plr::make_error(PLR_ERR_INVALID, r.error));
  }
  return results;
}

}  // namespace plr::chooser
