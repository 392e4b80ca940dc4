// Shared pieces of the kernel tests: an endpoint the test thread drives
// (test_endpoint.hpp), and configs that find the test plug-ins.
#pragma once

#include "bus.hpp"
#include "pipeline_config.hpp"
#include "test_endpoint.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>

#include <condition_variable>
#include <mutex>
#include <string>
#include <vector>

namespace plr::kernel::testing {

// A config whose plug-in path is the test plug-in folder.
PipelineConfig config_from_yaml(const std::string& yaml);

template <class T>
plr_msg* make_msg(const flatbuffers::FlatBufferBuilder& fbb) {
  return msg_copy(fbb.GetBufferPointer(), fbb.GetSize(), MessageTraits<T>::type_id(),
                  MessageTraits<T>::schema_version, 0);
}

plr_msg* make_double_request(std::int64_t value);

// Answers to numbered bus calls: how many each got, and the error texts.
// Tests derive to keep what the replies carry.
struct CallLedger {
  explicit CallLedger(std::size_t calls) : answers(calls, 0) {}
  std::mutex m;
  std::condition_variable cv;
  std::vector<int> answers;
  std::vector<std::string> errors;
  std::size_t completed = 0;

  // One answer to call `i`, `error` null when it succeeded; `m` is held.
  void count(std::size_t i, const char* error) {
    ++answers[i];
    if (error != nullptr) errors.emplace_back(error);
    ++completed;
    cv.notify_all();
  }
};

// The user pointer of call `index`.
template <class Ledger>
struct CallCtx {
  Ledger* ledger;
  std::size_t index;
};

// Collects the source strings of `lifecycle` reports, in arrival order.
class EventLog {
 public:
  static void on_message(void* user, const plr_msg* m);
  std::vector<std::string> wait_for(std::size_t n, int timeout_ms = 5000);

 private:
  std::mutex m_;
  std::condition_variable cv_;
  std::vector<std::string> events_;
};

// Runs a shell command, returns its exit code and what it printed (stdout+stderr).
int run_command(const std::string& command, std::string* output);

}  // namespace plr::kernel::testing
