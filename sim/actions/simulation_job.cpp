#include "plr/actions/simulation_job.hpp"

#include <plr/msg/generator_generated.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include <nlohmann/json.hpp>

#include "plr/sim/observation.hpp"

namespace plr::actions {

namespace {

namespace msg = plr::msg;

plr::Error bad(const std::string& origin, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, origin + ": " + what);
}

plr::jobs::Bytes finished(flatbuffers::FlatBufferBuilder& fbb) {
  return plr::jobs::Bytes(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
}

plr::Expected<StateBytes> state_of(const flatbuffers::Vector<std::uint8_t>* v,
                                   const std::string& origin, const char* what) {
  if (!v) return bad(origin, fmt::format("{}: state missing", what));
  if (!is_truck_state(v->data(), v->size()))
    return bad(origin, fmt::format("{}: state: not a TruckState", what));
  return std::make_shared<const std::vector<std::uint8_t>>(v->begin(), v->end());
}

// Looks at the simulation's state after `memory`'s actions.
plr::Expected<SimOutcome> describe(Rig& rig, const Memory& memory) {
  auto seen = rig.backend().observe();
  if (!seen) return seen.error();
  SimOutcome o;
  const sim::SceneAnalysis scene = rig.model().scene(*seen, memory);
  o.observation = scene.observation ? static_cast<int>(*scene.observation) : kEmptyObservation;
  o.boxes_left = static_cast<std::uint32_t>(seen->world.boxes.size());
  for (const sim::Box& b : seen->world.boxes) {
    o.highest_stack_m = std::max(o.highest_stack_m, sim::bounds(b).z1);
  }
  o.state = std::make_shared<const std::vector<std::uint8_t>>(rig.snapshot(memory));
  return o;
}

}  // namespace

bool is_truck_state(const std::uint8_t* data, std::size_t size) {
  flatbuffers::Verifier v(data, size);
  return v.VerifyBuffer<msg::TruckState>(nullptr);
}

plr::jobs::Bytes encode_sim_job(const SimJob& job) {
  flatbuffers::FlatBufferBuilder fbb(job.request.state->size() + 1024);
  const auto state = fbb.CreateVector(*job.request.state);
  const auto json = fbb.CreateString(job.observation_json);
  fbb.Finish(msg::CreateSimJob(fbb, state, job.request.action, json,
                               static_cast<std::uint8_t>(job.fidelity)));
  return finished(fbb);
}

plr::Expected<SimJob> decode_sim_job(const plr::jobs::Bytes& bytes, const std::string& origin) {
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  if (!verifier.VerifyBuffer<msg::SimJob>(nullptr)) return bad(origin, "not a SimJob");
  const auto* j = flatbuffers::GetRoot<msg::SimJob>(bytes.data());
  auto state = state_of(j->state(), origin, "job");
  if (!state) return state.error();
  if (static_cast<int>(j->action()) >= sim::kNumActions)
    return bad(origin, fmt::format("job: action {} out of range", static_cast<int>(j->action())));
  if (j->fidelity() > static_cast<std::uint8_t>(sim::Fidelity::kFast))
    return bad(origin, fmt::format("job: fidelity {} out of range", j->fidelity()));
  SimJob out;
  out.request = {*state, j->action()};
  out.fidelity = static_cast<sim::Fidelity>(j->fidelity());
  if (const auto* json = j->observation_json()) {
    if (json->size() > kMaxObservationJson) return bad(origin, "observation_json too long");
    out.observation_json = json->str();
  }
  return out;
}

plr::jobs::Bytes encode_sim_outcome(const SimOutcome& o) {
  flatbuffers::FlatBufferBuilder fbb(o.state ? o.state->size() + 256 : 256);
  const auto state = o.state ? fbb.CreateVector(*o.state) : 0;
  fbb.Finish(msg::CreateSimResult(fbb, state, o.applicable, o.boxes, o.robot_time_s,
                                  static_cast<std::int16_t>(o.observation), o.boxes_left,
                                  o.highest_stack_m, o.wall_s));
  return finished(fbb);
}

plr::Expected<SimOutcome> decode_sim_outcome(const plr::jobs::Bytes& bytes,
                                             const std::string& origin) {
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  if (!verifier.VerifyBuffer<msg::SimResult>(nullptr)) return bad(origin, "not a SimResult");
  const auto* r = flatbuffers::GetRoot<msg::SimResult>(bytes.data());
  auto state = state_of(r->state(), origin, "result");
  if (!state) return state.error();
  SimOutcome o;
  o.applicable = r->applicable();
  o.boxes = r->boxes();
  o.robot_time_s = r->robot_time_s();
  o.observation = r->observation();
  o.boxes_left = r->boxes_left();
  o.highest_stack_m = r->highest_stack_m();
  o.wall_s = r->wall_s();
  o.state = *state;
  if (o.observation < kEmptyObservation || o.observation >= sim::kNumObservations)
    return bad(origin, fmt::format("result: observation {} out of range", o.observation));
  if (!std::isfinite(o.robot_time_s) || o.robot_time_s < 0)
    return bad(origin, "result: robot_time_s must be finite and >= 0");
  return o;
}

plr::Expected<std::unique_ptr<Rig>> make_rig(const std::string& observation_json) {
  const auto parsed = nlohmann::json::parse(observation_json, nullptr, false);
  if (parsed.is_discarded() || !parsed.is_object())
    return plr::make_error(PLR_ERR_INVALID, "observation_json: not a JSON object");
  auto params = sim::ObservationParams::from_json(parsed);
  if (!params)
    return plr::make_error(PLR_ERR_INVALID, "observation_json: " + params.error().message);
  ActionOptions options;
  options.observation = *params;
  options.plan_timeout_s = kOfflinePlanTimeoutS;
  return Rig::create(std::move(options));
}

plr::Expected<SimOutcome> start_state(Rig& rig, const sim::World& truth) {
  rig.reset(truth);
  return describe(rig, {});
}

plr::Expected<SimOutcome> simulate(Rig& rig, const SimRequest& request) {
  const auto t0 = std::chrono::steady_clock::now();
  auto memory = rig.restore(*request.state);
  if (!memory) return memory.error();
  auto outcome = rig.model().run(request.action, rig.backend(), *memory);
  if (!outcome)
    return plr::make_error(outcome.error().code,
                           sim::to_string(request.action) + ": " + outcome.error().message);
  auto o = describe(rig, *memory);
  if (!o) return o.error();
  o->applicable = outcome->applicable;
  o->boxes = outcome->boxes;
  o->robot_time_s = outcome->robot_time_s;
  o->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

void add_sim_action(plr::jobs::Kinds& kinds) {
  struct Loaded {
    std::unique_ptr<Rig> rig;
    std::string observation_json;
  };
  auto loaded = std::make_shared<Loaded>();
  kinds.add(kSimActionKind,
            [loaded](const plr::jobs::Bytes& input) -> plr::Expected<plr::jobs::Bytes> {
              auto job = decode_sim_job(input, kSimActionKind);
              if (!job) return job.error();
              if (!loaded->rig || job->observation_json != loaded->observation_json) {
                auto rig = make_rig(job->observation_json);
                if (!rig) return rig.error();
                loaded->rig = std::move(*rig);
                loaded->observation_json = job->observation_json;
              }
              loaded->rig->set_fidelity(job->fidelity);
              auto outcome = simulate(*loaded->rig, job->request);
              if (!outcome) return outcome.error();
              return encode_sim_outcome(*outcome);
            });
}

std::uint64_t state_hash(const std::vector<std::uint8_t>& state) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const std::uint8_t b : state) {
    h ^= b;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::uint64_t work_key(std::uint64_t state_hash, sim::Action action, sim::Fidelity fidelity) {
  std::uint64_t z = state_hash ^ (static_cast<std::uint64_t>(action) + 1) * 0x9e3779b97f4a7c15ull ^
                    static_cast<std::uint64_t>(fidelity) * 0xd1b54a32d192ed03ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace plr::actions
