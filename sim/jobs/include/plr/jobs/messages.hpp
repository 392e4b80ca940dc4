// A job and its result as bytes (sdk/schemas/jobs.fbs): what goes over a
// worker's pipe and what a result store's file holds, each inside the frame
// of plr/frame.hpp.
#pragma once

#include <plr/expected.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

#include "plr/jobs/job.hpp"

namespace plr::jobs {

Bytes encode_request(std::uint64_t id, const Job& job);
Bytes encode_reply(std::uint64_t id, const Result& result);

struct Message {
  enum class Type { kRequest, kReply } type = Type::kRequest;
  std::uint64_t id = 0;
  Job job;        // kRequest
  Result result;  // kReply (stored stays false)
};

// The bytes of one message, untrusted: verified, sizes bounded, the key
// checked (valid_key). The error is one line, "<origin>: <cause>".
plr::Expected<Message> decode_message(const std::uint8_t* data, std::size_t size,
                                      const std::string& origin);

}  // namespace plr::jobs
