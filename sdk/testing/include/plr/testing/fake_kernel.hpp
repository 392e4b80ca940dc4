// An in-process, deterministic stand-in for the kernel, so a plug-in can be
// unit-tested alone. It implements plr_host_api the way the kernel does (same
// ownership and completion rules) but runs node callbacks only when the test
// calls spin(), on the test's thread, and keeps a manual clock: no sleeps.
//
//   plr::testing::FakeKernel k;
//   auto node = k.load_node("lib/plugins/demo_doubler.so",
//                           plr::testing::NodeOptions().with_params(R"({"factor": 3})"));
//   ASSERT_TRUE(node->configure());
//   ASSERT_TRUE(node->activate());
//   auto reply = k.call<plr::msg::DoubleRequest, plr::msg::DoubleReply>("double", request);
//   EXPECT_EQ(reply.value()->value(), 6);
//
// Rules it shares with the kernel, so tests see the real behaviour (the host
// contract suite, plr/testing/host_contract.hpp, checks both against them):
// - Topic messages and new service requests reach only active nodes; what a
//   node accepted while active reaches it before its deactivate hook runs
//   (deactivate() delivers it first, as the node's thread in the kernel does).
// - A node that is unconfigured (after cleanup or a failed configure) holds no
//   publishers, subscriptions or services: they are dropped, so the next
//   configure can register them again.
// - publish/call/respond take ownership of the message even when they fail.
// - A call with no active provider, or of the wrong request type, is refused:
//   call() returns the error and the reply callback never runs. Every other
//   call completes exactly once: reply, provider error, timeout, cancellation,
//   or "provider gone"; possibly before call() returns.
// - Several nodes may provide one service (as during a hot swap); the first
//   active one answers.
#pragma once

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>
#include <plr/message.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <flatbuffers/flatbuffers.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <typeinfo>
#include <vector>

namespace plr::testing {

struct NodeOptions {
  std::string name;                           // default: the plug-in's name, or "node"
  std::string params_json = "{}";             // what config `params:` would hold
  std::map<std::string, std::string> remaps;  // topic/service name -> name on the bus

  // Chainable, e.g. NodeOptions().with_params(R"({"factor": 3})").
  NodeOptions& with_name(std::string n) {
    name = std::move(n);
    return *this;
  }
  NodeOptions& with_params(std::string json) {
    params_json = std::move(json);
    return *this;
  }
  NodeOptions& with_remap(std::string from, std::string to) {
    remaps[std::move(from)] = std::move(to);
    return *this;
  }
};

struct KernelOptions {
  std::int64_t start_ns = 0;
  // Log lines at or above this level are echoed to stderr; all are kept in logs().
  plr_log_level echo_level = PLR_LOG_WARN;
};

struct LogLine {
  std::string node;
  plr_log_level level;
  std::string text;
};

// A copy of a message seen on the bus (the kernel's buffer is not kept alive).
struct Sample {
  std::string from;  // node name, or "test"
  std::string topic;
  std::uint64_t type_id = 0;
  std::uint32_t schema_version = 0;
  std::int64_t stamp_ns = 0;
  std::vector<std::uint8_t> bytes;

  // The message as T, or nullptr when it is not a valid T.
  template <class T>
  const T* as() const {
    if (type_id != MessageTraits<T>::type_id() || !verify<T>(bytes.data(), bytes.size()))
      return nullptr;
    return flatbuffers::GetRoot<T>(bytes.data());
  }
};

struct Rejection {
  std::string node;
  std::string reason;
};

struct PluginRef {
  const plr_plugin_descriptor* descriptor = nullptr;
  std::string path;
  // What the plug-in declares it offers (plr/interface.hpp); nullptr: nothing declared.
  const plr_interface* interface = nullptr;
};

// A topic a node advertised or a service it provided, under its resolved name.
struct Offer {
  std::string node;
  plr_port_kind kind = PLR_PORT_TOPIC;
  std::string name;
  std::uint64_t type_id = 0;        // a topic's message; a service's request
  std::uint64_t reply_type_id = 0;  // a service's reply; 0 for a topic
};

namespace detail {
struct Kernel;
struct Slot;
struct CallState;
}  // namespace detail

// A node living in a FakeKernel. Drives the life cycle through the node's C
// table exactly as the kernel does; errors carry the node's one-line text.
// Cheap to copy; valid while its kernel lives.
class NodeHandle {
 public:
  Status configure();
  Status activate();
  Status deactivate();
  Status cleanup();
  // What a kernel shutdown does: deactivate and clean up if needed, fail what
  // the node still has in flight, then destroy it.
  void destroy();

  // The state the kernel derived from successful transitions.
  NodeState state() const;
  bool alive() const;
  const std::string& name() const;
  // Calls this node made that have not completed yet.
  std::size_t pending_calls() const;
  // Requests delivered to this node's services and not answered yet.
  std::size_t unanswered_requests() const;

  // The C++ object of a node added with FakeKernel::add<N>(); aborts for
  // any other node, since its type is unknown.
  template <class N>
  N& get() const {
    return *static_cast<N*>(static_cast<Node*>(object_as(typeid(N))));
  }

 private:
  friend class FakeKernel;
  NodeHandle(detail::Kernel* k, detail::Slot* s) : kernel_(k), slot_(s) {}
  void* object_as(const std::type_info& type) const;
  Status transition(plr_status (*fn)(void*, char*, std::size_t), NodeState from, NodeState to,
                    const char* what);

  detail::Kernel* kernel_;
  detail::Slot* slot_;
};

// The eventual reply of a call made by the test.
template <class Rep>
class CallHandle {
 public:
  bool ready() const;
  // The reply, or the error the call completed with (PLR_ERR_STATE "still
  // pending" when it has not completed).
  Expected<Message<Rep>> result() const;

 private:
  friend class FakeKernel;
  explicit CallHandle(std::shared_ptr<detail::CallState> s) : state_(std::move(s)) {}
  std::shared_ptr<detail::CallState> state_;
};

class FakeKernel {
 public:
  explicit FakeKernel(KernelOptions options = {});
  // Shuts every live node down (NodeHandle::destroy), drops queued work and
  // unloads the plug-ins.
  ~FakeKernel();
  FakeKernel(const FakeKernel&) = delete;
  FakeKernel& operator=(const FakeKernel&) = delete;

  // --- Nodes ---------------------------------------------------------------
  // Opens a plug-in library by path and checks its entry point and ABI major.
  Expected<PluginRef> load(const std::string& path);
  // Creates a node from a loaded plug-in (the plug-in's create()).
  Expected<NodeHandle> create(const PluginRef& plugin, NodeOptions options = {});
  // load() then create().
  Expected<NodeHandle> load_node(const std::string& path, NodeOptions options = {});
  // Instantiates a Node subclass directly, behind the same C table a plug-in has.
  template <class N>
  NodeHandle add(NodeOptions options = {}) {
    static const plr_node_api api = {&plr::detail::PluginTrampolines<N>::create,
                                     &plr::detail::PluginTrampolines<N>::destroy,
                                     &plr::detail::PluginTrampolines<N>::configure,
                                     &plr::detail::PluginTrampolines<N>::activate,
                                     &plr::detail::PluginTrampolines<N>::deactivate,
                                     &plr::detail::PluginTrampolines<N>::cleanup};
    return add_node(api, &typeid(N), std::move(options));
  }

  // --- Running -------------------------------------------------------------
  // Delivers queued topic messages and service requests, and completes calls
  // whose deadline has passed, on this thread, until nothing is left.
  // Returns how many deliveries ran.
  std::size_t spin();
  // Delivers at most one queued item; false when there was none.
  bool spin_once();

  // --- Clock ---------------------------------------------------------------
  std::int64_t now_ns() const;
  void set_now(std::int64_t ns);
  // Moves the clock; calls whose timeout passed complete at the next spin().
  void advance(std::chrono::nanoseconds d);

  // --- Topics --------------------------------------------------------------
  // Publishes as the test; subscribers receive it at the next spin().
  template <class T>
  Status publish(const std::string& topic, const flatbuffers::FlatBufferBuilder& fbb) {
    return publish_raw(topic, MessageTraits<T>::type_id(), MessageTraits<T>::schema_version,
                       fbb.GetBufferPointer(), fbb.GetSize());
  }
  // Any bytes under any type id, e.g. to check that a node rejects garbage.
  Status publish_raw(const std::string& topic, std::uint64_t type_id, std::uint32_t schema_version,
                     const std::uint8_t* data, std::size_t size);
  // Everything published on `topic` so far, by nodes and by the test, in order.
  std::vector<Sample> published(const std::string& topic) const;
  void clear_published();
  // For nodes that publish from their own threads: waits (real time, no
  // polling) until `topic` has seen at least `n` messages; false on timeout.
  bool wait_published(const std::string& topic, std::size_t n, std::chrono::milliseconds timeout);
  std::size_t subscribers(const std::string& topic) const;
  std::size_t publishers(const std::string& topic) const;

  // --- Services ------------------------------------------------------------
  // Serves `service` from the test. The handler runs inside the node's call(),
  // on the calling thread, and its answer completes the call at once: fill
  // and Finish() `reply`, or return an error to script a failure.
  template <class Req, class Rep>
  void fake_service(const std::string& service,
                    std::function<Status(const Req&, flatbuffers::FlatBufferBuilder&)> handler) {
    add_fake_service(
        service, MessageTraits<Req>::type_id(), MessageTraits<Rep>::type_id(),
        [handler = std::move(handler)](const Sample& request,
                                       flatbuffers::FlatBufferBuilder& reply) {
          const Req* req = request.as<Req>();
          if (req == nullptr)
            return Status(make_error(PLR_ERR_INVALID, "request is not a valid " +
                                                          std::string(MessageTraits<Req>::name())));
          return handler(*req, reply);
        });
  }
  // A service that always fails with `code` and `message`.
  void fake_service_error(const std::string& service, plr_status code, const std::string& message);
  // Requests the nodes sent to `service` (fake or node-provided), in order.
  std::vector<Sample> requests(const std::string& service) const;
  bool has_provider(const std::string& service) const;
  // Every topic advertised and service provided by a node so far, in order
  // (kept after the node withdraws them).
  std::vector<Offer> offers() const;

  // Calls a service as the test. A node's handler runs at the next spin().
  template <class Req, class Rep>
  CallHandle<Rep> call_async(const std::string& service,
                             const flatbuffers::FlatBufferBuilder& request,
                             std::chrono::nanoseconds timeout = std::chrono::seconds(10)) {
    return CallHandle<Rep>(start_call(service, MessageTraits<Req>::type_id(),
                                      MessageTraits<Rep>::type_id(),
                                      MessageTraits<Req>::schema_version, request, timeout));
  }
  // call_async(), then spin() until it completes or nothing is left to run.
  template <class Req, class Rep>
  Expected<Message<Rep>> call(const std::string& service,
                              const flatbuffers::FlatBufferBuilder& request,
                              std::chrono::nanoseconds timeout = std::chrono::seconds(10)) {
    auto handle = call_async<Req, Rep>(service, request, timeout);
    while (!handle.ready() && spin_once()) {
    }
    return handle.result();
  }

  // --- What happened -------------------------------------------------------
  // Message buffers alive now (held by nodes, the queue or the test). Zero
  // once every node is destroyed, unless something leaked a reference.
  std::int64_t live_messages() const;
  std::size_t pending_calls() const;
  std::vector<LogLine> logs() const;
  // Messages nodes rejected through reject() (failed verification).
  std::vector<Rejection> rejections() const;

  // The host table given to the test's own Message<T> copies.
  const plr_host_api* test_api() const;

 private:
  NodeHandle add_node(const plr_node_api& api, const std::type_info* type, NodeOptions options);
  void add_fake_service(const std::string& service, std::uint64_t request_type,
                        std::uint64_t reply_type,
                        std::function<Status(const Sample&, flatbuffers::FlatBufferBuilder&)> fn);
  std::shared_ptr<detail::CallState> start_call(const std::string& service,
                                                std::uint64_t request_type,
                                                std::uint64_t reply_type,
                                                std::uint32_t schema_version,
                                                const flatbuffers::FlatBufferBuilder& request,
                                                std::chrono::nanoseconds timeout);

  std::unique_ptr<detail::Kernel> k_;
};

namespace detail {

// The completion of a call made by the test; shared with the kernel.
struct CallState {
  mutable std::mutex m;
  bool done = false;
  plr_status status = PLR_OK;
  std::string error;
  const plr_msg* reply = nullptr;  // one reference, released with the state
  const plr_host_api* api = nullptr;
  ~CallState();
};

}  // namespace detail

template <class Rep>
bool CallHandle<Rep>::ready() const {
  std::lock_guard lock(state_->m);
  return state_->done;
}

template <class Rep>
Expected<Message<Rep>> CallHandle<Rep>::result() const {
  std::lock_guard lock(state_->m);
  if (!state_->done) return make_error(PLR_ERR_STATE, "call still pending");
  if (state_->status != PLR_OK) return make_error(state_->status, state_->error);
  const auto v = state_->api->msg_view(state_->reply);
  if (v.type_id != MessageTraits<Rep>::type_id() || !verify<Rep>(v.data, v.size))
    return make_error(PLR_ERR_INVALID,
                      "reply is not a valid " + std::string(MessageTraits<Rep>::name()));
  return Message<Rep>(state_->api, state_->reply);
}

}  // namespace plr::testing
