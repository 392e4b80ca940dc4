#include "plr/actions/simulation_job.hpp"

#include <plr/msg/generator_generated.h>

#include <fmt/format.h>

namespace plr::actions {

namespace {

namespace msg = plr::msg;

std::vector<std::uint8_t> with_size(const flatbuffers::FlatBufferBuilder& fbb) {
  const auto n = static_cast<std::uint32_t>(fbb.GetSize());
  std::vector<std::uint8_t> out;
  out.reserve(n + 4);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(n >> (8 * i)));
  out.insert(out.end(), fbb.GetBufferPointer(), fbb.GetBufferPointer() + n);
  return out;
}

plr::Error bad(const std::string& origin, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, origin + ": " + what);
}

}  // namespace

bool is_truck_state(const std::uint8_t* data, std::size_t size) {
  flatbuffers::Verifier v(data, size);
  return v.VerifyBuffer<msg::TruckState>(nullptr);
}

std::vector<std::uint8_t> frame_setup(const std::string& observation_json) {
  flatbuffers::FlatBufferBuilder fbb;
  const auto setup = msg::CreateWorkerSetup(fbb, fbb.CreateString(observation_json));
  msg::FinishWorkerFrameBuffer(
      fbb, msg::CreateWorkerFrame(fbb, msg::WorkerMessage::WorkerSetup, setup.Union()));
  return with_size(fbb);
}

void build_job(flatbuffers::FlatBufferBuilder& fbb, std::uint64_t id, const SimRequest& request,
               const std::string& observation_json) {
  const auto state = fbb.CreateVector(*request.state);
  const auto json = observation_json.empty() ? 0 : fbb.CreateString(observation_json);
  const auto job = msg::CreateSimJob(fbb, id, state, request.action, json);
  msg::FinishWorkerFrameBuffer(
      fbb, msg::CreateWorkerFrame(fbb, msg::WorkerMessage::SimJob, job.Union()));
}

std::vector<std::uint8_t> frame_job(std::uint64_t id, const SimRequest& request) {
  flatbuffers::FlatBufferBuilder fbb(request.state->size() + 256);
  build_job(fbb, id, request);
  return with_size(fbb);
}

std::vector<std::uint8_t> frame_result(std::uint64_t id, const plr::Expected<SimOutcome>& result) {
  flatbuffers::FlatBufferBuilder fbb(result && result->state ? result->state->size() + 256 : 256);
  build_result(fbb, id, result);
  return with_size(fbb);
}

void build_result(flatbuffers::FlatBufferBuilder& fbb, std::uint64_t id,
                  const plr::Expected<SimOutcome>& result) {
  flatbuffers::Offset<msg::SimResult> r;
  if (!result) {
    r = msg::CreateSimResult(fbb, id, fbb.CreateString(result.error().message));
  } else {
    const SimOutcome& o = *result;
    const auto state = o.state ? fbb.CreateVector(*o.state) : 0;
    r = msg::CreateSimResult(fbb, id, 0, state, o.applicable, o.boxes, o.robot_time_s,
                             static_cast<std::int16_t>(o.observation), o.boxes_left,
                             o.highest_stack_m, o.wall_s);
  }
  msg::FinishWorkerFrameBuffer(
      fbb, msg::CreateWorkerFrame(fbb, msg::WorkerMessage::SimResult, r.Union()));
}

plr::Expected<Frame> decode_frame(const std::uint8_t* data, std::size_t size,
                                  const std::string& origin) {
  if (size > kMaxFrameBytes) return bad(origin, fmt::format("frame of {} bytes", size));
  flatbuffers::Verifier verifier(data, size);
  // The identifier sits at bytes 4..8: a shorter frame has none to compare.
  if (size < 8 || !msg::WorkerFrameBufferHasIdentifier(data) ||
      !msg::VerifyWorkerFrameBuffer(verifier))
    return bad(origin, "frame fails verification");
  const msg::WorkerFrame* f = msg::GetWorkerFrame(data);
  Frame out;
  auto json_of = [&](const flatbuffers::String* json, std::string& to) -> plr::Status {
    if (json == nullptr) return {};
    if (json->size() > kMaxObservationJson) return bad(origin, "observation_json too long");
    to = json->str();
    return {};
  };
  auto state_of = [&](const flatbuffers::Vector<std::uint8_t>* v) -> plr::Expected<StateBytes> {
    if (!v) return StateBytes{};
    if (!is_truck_state(v->data(), v->size())) return bad(origin, "state: not a TruckState");
    return std::make_shared<const std::vector<std::uint8_t>>(v->begin(), v->end());
  };
  // A union's type may be set with its table absent: verification passes that.
  if (f->message() == nullptr) return bad(origin, "frame without a message");
  switch (f->message_type()) {
    case msg::WorkerMessage::WorkerSetup: {
      const auto* s = f->message_as_WorkerSetup();
      out.kind = Frame::Kind::kSetup;
      out.observation_json = "{}";
      if (auto ok = json_of(s->observation_json(), out.observation_json); !ok) return ok.error();
      return out;
    }
    case msg::WorkerMessage::SimJob: {
      const auto* j = f->message_as_SimJob();
      out.kind = Frame::Kind::kJob;
      out.id = j->id();
      auto state = state_of(j->state());
      if (!state) return state.error();
      if (!*state) return bad(origin, "job: state missing");
      if (static_cast<int>(j->action()) >= sim::kNumActions)
        return bad(origin,
                   fmt::format("job: action {} out of range", static_cast<int>(j->action())));
      out.request = {*state, j->action()};
      if (auto ok = json_of(j->observation_json(), out.observation_json); !ok) return ok.error();
      return out;
    }
    case msg::WorkerMessage::SimResult: {
      const auto* r = f->message_as_SimResult();
      out.kind = Frame::Kind::kResult;
      out.id = r->id();
      if (r->error()) {
        out.result = plr::make_error(PLR_ERR_INTERNAL, r->error()->str());
        return out;
      }
      auto state = state_of(r->state());
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
      if (!o.state) return bad(origin, "result: state missing");
      out.result = std::move(o);
      return out;
    }
    default:
      return bad(origin, "frame holds no message");
  }
}

std::uint64_t state_hash(const std::vector<std::uint8_t>& state) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const std::uint8_t b : state) {
    h ^= b;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::uint64_t work_key(std::uint64_t state_hash, sim::Action action) {
  std::uint64_t z = state_hash ^ (static_cast<std::uint64_t>(action) + 1) * 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace plr::actions
