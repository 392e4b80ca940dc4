// What a node sees of the kernel: typed topics and services, parameters, a
// logger and the pipeline's clock. Everything goes through the C host table,
// so a node never depends on where its peers run.
#pragma once

#include <plr/expected.hpp>
#include <plr/loan.hpp>
#include <plr/message.hpp>
#include <plr/params.hpp>
#include <plr/spin_wait.hpp>

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace plr {

using namespace std::chrono_literals;

namespace detail {

// Copies a finished builder into a kernel buffer; the only copy on the
// in-process path (subscribers then share that buffer).
inline plr_msg* to_kernel(const plr_host_api* api, const flatbuffers::FlatBufferBuilder& fbb,
                          std::size_t* size) {
  *size = fbb.GetSize();
  std::uint8_t* data = nullptr;
  plr_msg* msg = api->msg_alloc(api->ctx, *size, &data);
  if (msg != nullptr) std::memcpy(data, fbb.GetBufferPointer(), *size);
  return msg;
}

inline Status to_status(plr_status code, std::string what) {
  if (code == PLR_OK) return {};
  return make_error(code, std::move(what));
}

}  // namespace detail

class Logger {
 public:
  explicit Logger(const plr_host_api* api) : api_(api) {}
  template <class... A>
  void debug(fmt::format_string<A...> f, A&&... a) const {
    write(PLR_LOG_DEBUG, fmt::format(f, std::forward<A>(a)...));
  }
  template <class... A>
  void info(fmt::format_string<A...> f, A&&... a) const {
    write(PLR_LOG_INFO, fmt::format(f, std::forward<A>(a)...));
  }
  template <class... A>
  void warn(fmt::format_string<A...> f, A&&... a) const {
    write(PLR_LOG_WARN, fmt::format(f, std::forward<A>(a)...));
  }
  template <class... A>
  void error(fmt::format_string<A...> f, A&&... a) const {
    write(PLR_LOG_ERROR, fmt::format(f, std::forward<A>(a)...));
  }
  void write(plr_log_level level, const std::string& text) const {
    api_->log(api_->ctx, level, text.c_str());
  }

 private:
  const plr_host_api* api_;
};

template <class T>
class Publisher {
 public:
  Publisher() = default;
  Publisher(const plr_host_api* api, std::uint64_t id) : api_(api), id_(id) {}

  // A buffer to build the next message in (see plr/loan.hpp): no copy on
  // publish, also not into shared memory when another process reads the topic.
  Expected<Loan> loan(std::size_t max_bytes) const {
    std::uint8_t* data = nullptr;
    plr_msg* msg = api_->loan(api_->ctx, id_, max_bytes, &data);
    if (msg == nullptr) return make_error(PLR_ERR_UNAVAILABLE, "loan: no buffer available");
    return Loan(api_, id_, msg, data, max_bytes);
  }

  // Publishes a finished builder (fbb.Finish(root) done by the caller): one
  // copy, into the loaned buffer.
  Status publish(const flatbuffers::FlatBufferBuilder& fbb) const {
    std::uint8_t* data = nullptr;
    const std::size_t size = fbb.GetSize();
    plr_msg* msg = api_->loan(api_->ctx, id_, size, &data);
    if (msg == nullptr) return make_error(PLR_ERR_UNAVAILABLE, "publish: no buffer available");
    std::memcpy(data, fbb.GetBufferPointer(), size);
    return detail::to_status(api_->publish(api_->ctx, id_, msg, 0, size), "publish failed");
  }

 private:
  const plr_host_api* api_ = nullptr;
  std::uint64_t id_ = 0;
};

// The eventual reply of a call. The kernel always completes a call: with the
// reply, an error from the provider, a timeout, or a cancellation.
template <class T>
class Future {
  struct State {
    std::mutex m;
    std::condition_variable cv;
    std::atomic<bool> done{false};
    std::optional<Expected<Message<T>>> result;
    const plr_host_api* api = nullptr;
    std::uint64_t call = 0;
  };

 public:
  Future() = default;

  bool valid() const { return state_ != nullptr; }
  bool ready() const { return state_->done.load(std::memory_order_acquire); }
  // Waits for completion; the kernel's timeout bounds the wait. It watches
  // for the reply for `spin` (a core kept busy) before it sleeps, since a
  // sleeping thread is woken late (spin_wait.hpp).
  Expected<Message<T>> get(std::chrono::nanoseconds spin = kCallSpin) const {
    if (!spin_until(state_->done, spin)) {
      std::unique_lock lock(state_->m);
      state_->cv.wait(lock, [&] { return state_->done.load(std::memory_order_relaxed); });
    }
    std::lock_guard lock(state_->m);
    return *state_->result;
  }
  bool wait_for(std::chrono::nanoseconds d) const {
    std::unique_lock lock(state_->m);
    return state_->cv.wait_for(lock, d,
                               [&] { return state_->done.load(std::memory_order_relaxed); });
  }
  // Cancels a call still in flight; a no-op once it completed or was refused.
  void cancel() const {
    if (!state_ || state_->api == nullptr || ready()) return;
    state_->api->cancel(state_->api->ctx, state_->call);
  }

 private:
  friend class Context;

  static Future failed(Error e) {
    Future f;
    f.state_ = std::make_shared<State>();
    f.state_->result.emplace(std::move(e));
    f.state_->done = true;
    return f;
  }

  // Runs on a kernel thread; the state is shared with the caller's Future.
  static void complete(void* user, plr_status status, const plr_msg* reply, const char* error) {
    auto* holder = static_cast<std::shared_ptr<State>*>(user);
    std::shared_ptr<State> state = std::move(*holder);
    delete holder;
    Expected<Message<T>> result = make_error(status, error ? error : "call failed");
    if (status == PLR_OK) {
      const auto v = state->api->msg_view(reply);
      if (verify<T>(v.data, v.size)) {
        result = Message<T>(state->api, reply);
      } else {
        state->api->reject(state->api->ctx, reply, "reply failed verification");
        result = make_error(PLR_ERR_INVALID, "reply failed verification");
      }
    }
    {
      // Set under the lock (a sleeper checks it there) and after the result
      // (a spinner reads the result once it sees the flag).
      std::lock_guard lock(state->m);
      state->result.emplace(std::move(result));
      state->done.store(true, std::memory_order_release);
    }
    state->cv.notify_all();
  }

  std::shared_ptr<State> state_;
};

// Answers one service request exactly once. A responder dropped without an
// answer answers with an error, so no caller waits forever.
template <class T>
class Responder {
 public:
  Responder(const plr_host_api* api, std::uint64_t token) : api_(api), token_(token) {}
  Responder(Responder&& o) noexcept : api_(o.api_), token_(std::exchange(o.token_, 0)) {}
  Responder& operator=(Responder&&) = delete;
  Responder(const Responder&) = delete;
  ~Responder() {
    if (token_ != 0) (void)fail(PLR_ERR_INTERNAL, "provider dropped the request unanswered");
  }

  Status reply(const flatbuffers::FlatBufferBuilder& fbb) {
    std::size_t size = 0;
    plr_msg* msg = detail::to_kernel(api_, fbb, &size);
    const auto token = std::exchange(token_, 0);
    return detail::to_status(api_->respond(api_->ctx, token, PLR_OK, msg, 0, size, nullptr),
                             "respond failed");
  }
  Status fail(plr_status code, const std::string& why) {
    const auto token = std::exchange(token_, 0);
    return detail::to_status(api_->respond(api_->ctx, token, code, nullptr, 0, 0, why.c_str()),
                             "respond failed");
  }

 private:
  const plr_host_api* api_;
  std::uint64_t token_;
};

// kQuick: the handler answers at once and never waits (no blocking call,
// no sleep), so the kernel may run it on the thread that received the
// request instead of handing it to the node's thread (PLR_SERVICE_QUICK).
enum class ServiceMode { kNormal, kQuick };

class Context {
 public:
  explicit Context(const plr_host_api* api)
      : api_(api), log_(api), params_(nlohmann::json::parse(api->params_json(api->ctx))) {}
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  template <class T>
  Expected<Publisher<T>> advertise(const std::string& topic) {
    std::uint64_t id = 0;
    const auto s = api_->advertise(api_->ctx, topic.c_str(), MessageTraits<T>::type_id(),
                                   MessageTraits<T>::schema_version, &id);
    if (s != PLR_OK) return make_error(s, "advertise '" + topic + "' failed");
    return Publisher<T>(api_, id);
  }

  template <class T>
  Status subscribe(const std::string& topic, std::function<void(const Message<T>&)> fn) {
    auto handler = std::make_unique<Callback<T>>(api_, std::move(fn));
    std::uint64_t id = 0;
    const auto s = api_->subscribe(api_->ctx, topic.c_str(), MessageTraits<T>::type_id(),
                                   &Callback<T>::on_message, handler.get(), &id);
    if (s != PLR_OK) return make_error(s, "subscribe '" + topic + "' failed");
    callbacks_.push_back(std::move(handler));
    return {};
  }

  // A synchronous provider: fill `reply` (Finish() it) or return an error.
  template <class Req, class Rep>
  Status provide(const std::string& service,
                 std::function<Status(const Message<Req>&, flatbuffers::FlatBufferBuilder&)> fn,
                 ServiceMode mode = ServiceMode::kNormal) {
    return provide_async<Req, Rep>(
        service,
        [fn = std::move(fn)](const Message<Req>& req, Responder<Rep> r) {
          flatbuffers::FlatBufferBuilder fbb;
          if (auto s = fn(req, fbb); s) {
            (void)r.reply(fbb);
          } else {
            (void)r.fail(s.error().code, s.error().message);
          }
        },
        mode);
  }

  // An asynchronous provider: keep the Responder and answer later, from any thread.
  template <class Req, class Rep>
  Status provide_async(const std::string& service,
                       std::function<void(const Message<Req>&, Responder<Rep>)> fn,
                       ServiceMode mode = ServiceMode::kNormal) {
    auto handler = std::make_unique<Service<Req, Rep>>(api_, std::move(fn));
    const auto req_type = MessageTraits<Req>::type_id();
    const auto rep_type = MessageTraits<Rep>::type_id();
    const auto version = MessageTraits<Req>::schema_version;
    // A kernel older than ABI 1.1 runs every handler on the node's thread.
    const auto s =
        mode == ServiceMode::kQuick && api_->abi_minor >= 1
            ? api_->provide_flags(api_->ctx, service.c_str(), req_type, rep_type, version,
                                  &Service<Req, Rep>::on_request, handler.get(), PLR_SERVICE_QUICK)
            : api_->provide(api_->ctx, service.c_str(), req_type, rep_type, version,
                            &Service<Req, Rep>::on_request, handler.get());
    if (s != PLR_OK) return make_error(s, "provide '" + service + "' failed");
    callbacks_.push_back(std::move(handler));
    return {};
  }

  template <class Req, class Rep>
  Future<Rep> call(const std::string& service, const flatbuffers::FlatBufferBuilder& request,
                   std::chrono::nanoseconds timeout = 10s) {
    std::size_t size = 0;
    plr_msg* msg = detail::to_kernel(api_, request, &size);
    Future<Rep> f;
    f.state_ = std::make_shared<typename Future<Rep>::State>();
    f.state_->api = api_;
    auto* holder = new std::shared_ptr<typename Future<Rep>::State>(f.state_);
    std::uint64_t id = 0;
    const auto s = api_->call(api_->ctx, service.c_str(), MessageTraits<Req>::type_id(),
                              MessageTraits<Req>::schema_version, msg, 0, size, timeout.count(),
                              &Future<Rep>::complete, holder, &id);
    if (s != PLR_OK) {
      delete holder;
      return Future<Rep>::failed(make_error(s, "call '" + service + "' refused"));
    }
    std::lock_guard lock(f.state_->m);
    f.state_->call = id;
    return f;
  }

  const Params& params() const { return params_; }
  const Logger& log() const { return log_; }
  std::int64_t now_ns() const { return api_->now_ns(api_->ctx); }
  std::string name() const { return api_->node_name(api_->ctx); }
  const plr_host_api* api() const { return api_; }

 private:
  struct Handler {
    virtual ~Handler() = default;
  };

  template <class T>
  struct Callback : Handler {
    Callback(const plr_host_api* a, std::function<void(const Message<T>&)> f)
        : api(a), fn(std::move(f)) {}
    static void on_message(void* user, const plr_msg* msg) {
      auto* self = static_cast<Callback*>(user);
      const auto v = self->api->msg_view(msg);
      if (v.type_id != MessageTraits<T>::type_id() || !verify<T>(v.data, v.size)) {
        self->api->reject(self->api->ctx, msg, "message failed verification");
        return;
      }
      try {
        self->fn(Message<T>(self->api, msg));
      } catch (const std::exception& e) {
        Logger(self->api).error("subscription callback threw: {}", e.what());
      }
    }
    const plr_host_api* api;
    std::function<void(const Message<T>&)> fn;
  };

  template <class Req, class Rep>
  struct Service : Handler {
    Service(const plr_host_api* a, std::function<void(const Message<Req>&, Responder<Rep>)> f)
        : api(a), fn(std::move(f)) {}
    static void on_request(void* user, const plr_msg* msg, std::uint64_t token) {
      auto* self = static_cast<Service*>(user);
      Responder<Rep> responder(self->api, token);
      const auto v = self->api->msg_view(msg);
      if (!verify<Req>(v.data, v.size)) {
        self->api->reject(self->api->ctx, msg, "request failed verification");
        (void)responder.fail(PLR_ERR_INVALID, "request failed verification");
        return;
      }
      try {
        self->fn(Message<Req>(self->api, msg), std::move(responder));
      } catch (const std::exception& e) {
        Logger(self->api).error("service handler threw: {}", e.what());
      }
    }
    const plr_host_api* api;
    std::function<void(const Message<Req>&, Responder<Rep>)> fn;
  };

  const plr_host_api* api_;
  Logger log_;
  Params params_;
  std::vector<std::unique_ptr<Handler>> callbacks_;
};

}  // namespace plr
