#include "plr/jobs/messages.hpp"

#include <plr/msg/jobs_generated.h>

#include <fmt/format.h>

#include <cmath>
#include <cstring>

namespace plr::jobs {

namespace {

namespace msg = plr::msg;

Bytes finished(flatbuffers::FlatBufferBuilder& fbb, msg::JobMessage type,
               flatbuffers::Offset<void> message) {
  msg::FinishJobFrameBuffer(fbb, msg::CreateJobFrame(fbb, type, message));
  return Bytes(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
}

plr::Error bad(const std::string& origin, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, origin + ": " + what);
}

}  // namespace

Bytes encode_request(std::uint64_t id, const Job& job) {
  flatbuffers::FlatBufferBuilder fbb(job.input.size() + 256);
  const auto request = msg::CreateJobRequest(
      fbb, id, fbb.CreateString(job.kind), fbb.CreateString(job.key), fbb.CreateVector(job.input));
  return finished(fbb, msg::JobMessage::JobRequest, request.Union());
}

Bytes encode_reply(std::uint64_t id, const Result& result) {
  flatbuffers::FlatBufferBuilder fbb(result.output.size() + result.error.size() + 256);
  const auto reply = msg::CreateJobReply(fbb, id, fbb.CreateString(result.key), result.ok,
                                         result.ok ? fbb.CreateVector(result.output) : 0,
                                         result.ok ? 0 : fbb.CreateString(result.error),
                                         result.wall_s, result.attempts);
  return finished(fbb, msg::JobMessage::JobReply, reply.Union());
}

plr::Expected<Message> decode_message(const std::uint8_t* data, std::size_t size,
                                      const std::string& origin) {
  if (size > kMaxBytes + 4096) return bad(origin, fmt::format("message of {} bytes", size));
  // The identifier sits at bytes 4..8: a shorter buffer has none to compare.
  if (size < 8) return bad(origin, fmt::format("message of {} bytes is too short", size));
  // FlatBuffers reads scalars in place: a buffer off an 8-byte boundary is
  // read from an aligned copy.
  std::vector<std::uint64_t> aligned;
  if (reinterpret_cast<std::uintptr_t>(data) % alignof(std::uint64_t) != 0) {
    aligned.resize((size + 7) / 8);
    std::memcpy(aligned.data(), data, size);
    data = reinterpret_cast<const std::uint8_t*>(aligned.data());
  }
  flatbuffers::Verifier verifier(data, size);
  if (!msg::JobFrameBufferHasIdentifier(data) || !msg::VerifyJobFrameBuffer(verifier))
    return bad(origin, "not a job message (fails verification)");
  const msg::JobFrame* f = msg::GetJobFrame(data);
  // A union's type may be set with its table absent: verification passes that.
  if (f->message() == nullptr) return bad(origin, "a frame without a message");
  auto key_of = [&](const flatbuffers::String* key) -> plr::Expected<std::string> {
    if (key == nullptr || !valid_key(key->string_view()))
      return bad(origin, "key missing or not a valid file name");
    return key->str();
  };
  Message out;
  switch (f->message_type()) {
    case msg::JobMessage::JobRequest: {
      const auto* r = f->message_as_JobRequest();
      out.type = Message::Type::kRequest;
      out.id = r->id();
      auto key = key_of(r->key());
      if (!key) return key.error();
      if (r->kind() == nullptr || r->kind()->size() == 0 || r->kind()->size() > kMaxKey)
        return bad(origin, "request: kind missing or too long");
      out.job.kind = r->kind()->str();
      out.job.key = std::move(*key);
      if (r->input()) out.job.input.assign(r->input()->begin(), r->input()->end());
      return out;
    }
    case msg::JobMessage::JobReply: {
      const auto* r = f->message_as_JobReply();
      out.type = Message::Type::kReply;
      out.id = r->id();
      auto key = key_of(r->key());
      if (!key) return key.error();
      Result& result = out.result;
      result.key = std::move(*key);
      result.ok = r->ok();
      if (result.ok && r->output()) result.output.assign(r->output()->begin(), r->output()->end());
      if (!result.ok) result.error = r->error() ? r->error()->str() : "failed (no message)";
      result.wall_s = r->wall_s();
      result.attempts = r->attempts();
      if (!std::isfinite(result.wall_s) || result.wall_s < 0)
        return bad(origin, "reply: wall_s must be finite and >= 0");
      return out;
    }
    default:
      return bad(origin, "a frame of an unknown message");
  }
}

}  // namespace plr::jobs
