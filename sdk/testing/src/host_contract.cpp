#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/testing/host_contract.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace plr::testing {
namespace {

using namespace std::chrono_literals;
using msg::Count;
using msg::DoubleReply;
using msg::DoubleRequest;

// What the nodes and the test side saw, in order; shared by every thread.
class Journal {
 public:
  static Journal& get() {
    static Journal journal;
    return journal;
  }
  void reset() {
    std::lock_guard lock(m_);
    events_.clear();
  }
  void add(std::string event) {
    std::lock_guard lock(m_);
    events_.push_back(std::move(event));
  }
  std::vector<std::string> all() const {
    std::lock_guard lock(m_);
    return events_;
  }
  // The events starting with `prefix`, in order.
  std::vector<std::string> with(const std::string& prefix) const {
    std::lock_guard lock(m_);
    std::vector<std::string> out;
    for (const auto& e : events_)
      if (e.rfind(prefix, 0) == 0) out.push_back(e);
    return out;
  }
  bool has(const std::string& event) const {
    std::lock_guard lock(m_);
    return std::find(events_.begin(), events_.end(), event) != events_.end();
  }

 private:
  mutable std::mutex m_;
  std::vector<std::string> events_;
};

void note(const std::string& event) {
  Journal::get().add(event);
}

flatbuffers::FlatBufferBuilder count(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateCount(fbb, v));
  return fbb;
}

flatbuffers::FlatBufferBuilder double_request(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateDoubleRequest(fbb, v));
  return fbb;
}

// The node of the suite; what it does is set by its parameters:
//   in -> out (value + 1), serves `double` (value * factor; `quick`: as a quick
//   service; `fail_odd`: refuses odd values), `slow` (holds each request until
//   a message on `answer` says what to reply), `later` (answers from a thread
//   of its own), `drop` (drops the responder); `fail_configure_once`,
//   `throw_on` (a subscription callback that throws on that value).
class Probe : public Node {
 public:
  explicit Probe(const plr_host_api* host) : Node(host), name_(ctx().name()) {}
  ~Probe() override {
    for (auto& t : threads_) t.join();
    note(name_ + ":destroyed");
  }

 protected:
  Status on_configure() override {
    params().allow_only(
        {"factor", "quick", "fail_odd", "fail_configure_once", "throw_on", "provide"});
    note(name_ + ":configure " + params().json().dump());
    factor_ = params().get<std::int64_t>("factor", 2);
    throw_on_ = params().get<std::int64_t>("throw_on", -1);
    auto out = ctx().advertise<Count>("out");
    if (!out) return out.error();
    out_ = *out;
    if (auto s = ctx().subscribe<Count>("in", [this](const Message<Count>& m) { on_in(m); }); !s)
      return s;
    if (params().get<bool>("provide", true)) {
      const bool fail_odd = params().get<bool>("fail_odd", false);
      if (auto s = ctx().provide<DoubleRequest, DoubleReply>(
              "double",
              [this, fail_odd](const Message<DoubleRequest>& req,
                               flatbuffers::FlatBufferBuilder& reply) -> Status {
                note(name_ + ":double " + std::to_string(req->value()));
                if (fail_odd && req->value() % 2 != 0)
                  return make_error(PLR_ERR_INVALID, "odd request " + std::to_string(req->value()));
                reply.Finish(msg::CreateDoubleReply(reply, req->value() * factor_));
                return {};
              },
              params().get<bool>("quick", false) ? ServiceMode::kQuick : ServiceMode::kNormal);
          !s)
        return s;
    }
    if (auto s = provide_held(); !s) return s;
    if (params().get<bool>("fail_configure_once", false) && configures_++ == 0)
      return make_error(PLR_ERR_INVALID, "first configure refused on purpose");
    return {};
  }
  Status on_activate() override {
    note(name_ + ":activate");
    return {};
  }
  Status on_deactivate() override {
    note(name_ + ":deactivate");
    return {};
  }
  Status on_cleanup() override {
    note(name_ + ":cleanup");
    return {};
  }

 private:
  void on_in(const Message<Count>& m) {
    note(name_ + ":in " + std::to_string(m->value()));
    if (m->value() == throw_on_) throw std::runtime_error("a callback that throws");
    (void)out_.publish(count(m->value() + 1));
  }

  Status provide_held() {
    auto s = ctx().provide_async<DoubleRequest, DoubleReply>(
        "slow", [this](const Message<DoubleRequest>&, Responder<DoubleReply> r) {
          note(name_ + ":holding");
          held_.push_back(std::move(r));
        });
    if (!s) return s;
    s = ctx().subscribe<Count>("answer", [this](const Message<Count>& m) {
      for (auto& r : held_) {
        flatbuffers::FlatBufferBuilder fbb;
        fbb.Finish(msg::CreateDoubleReply(fbb, m->value()));
        const Status answered = r.reply(fbb);
        note(name_ + (answered ? ":answered" : ":answer refused"));
      }
      held_.clear();
    });
    if (!s) return s;
    s = ctx().provide_async<DoubleRequest, DoubleReply>(
        "later", [this](const Message<DoubleRequest>& req, Responder<DoubleReply> r) {
          threads_.emplace_back([r = std::move(r), v = req->value()]() mutable {
            flatbuffers::FlatBufferBuilder fbb;
            fbb.Finish(msg::CreateDoubleReply(fbb, v * 10));
            (void)r.reply(fbb);
          });
        });
    if (!s) return s;
    return ctx().provide_async<DoubleRequest, DoubleReply>(
        "drop", [](const Message<DoubleRequest>&, Responder<DoubleReply>) {});
  }

  std::string name_;
  std::int64_t factor_ = 2;
  std::int64_t throw_on_ = -1;
  int configures_ = 0;
  Publisher<Count> out_;
  std::vector<Responder<DoubleReply>> held_;
  std::vector<std::thread> threads_;
};

const plr_plugin_descriptor& probe_plugin() {
  using T = plr::detail::PluginTrampolines<Probe>;
  static const plr_plugin_descriptor descriptor = {
      PLR_ABI_MAJOR,
      PLR_ABI_MINOR,
      "contract_probe",
      "1.0.0",
      "the host contract suite's node",
      PLR_KIND_OTHER,
      {&T::create, &T::destroy, &T::configure, &T::activate, &T::deactivate, &T::cleanup}};
  return descriptor;
}

// One test's host and the test's own side of it. The host goes first: the
// test's handlers must outlive every delivery to them.
struct Session {
  explicit Session(const ContractHostFactory& make) {
    Journal::get().reset();
    host = make();
    test = std::make_unique<Context>(host->test_api());
  }
  ~Session() { host.reset(); }

  // An added node, configured and activated.
  void start(const std::string& name, const std::string& params = "{}",
             const std::map<std::string, std::string>& remaps = {}) {
    ASSERT_TRUE(host->add(probe_plugin(), name, params, remaps));
    const Status configured = host->configure(name);
    ASSERT_TRUE(configured) << configured.error().message;
    ASSERT_TRUE(host->activate(name));
  }
  // Lets the host work until `done` holds (bounded: 5 s on its clock).
  bool until(const std::function<bool()>& done) {
    for (int i = 0; i < 5000 && !done(); ++i) host->run(1ms);
    return done();
  }
  // Lets the host deliver what is due now.
  void settle() {
    for (int i = 0; i < 3; ++i) host->run(0ns);
  }
  void publish(const std::string& topic, std::int64_t value) {
    auto p = test->advertise<Count>(topic);
    ASSERT_TRUE(p) << p.error().message;
    ASSERT_TRUE(p->publish(count(value)));
  }
  Future<DoubleReply> call(const std::string& service, std::int64_t value,
                           std::chrono::nanoseconds timeout = 10s) {
    return test->call<DoubleRequest, DoubleReply>(service, double_request(value), timeout);
  }
  Expected<Message<DoubleReply>> result(const Future<DoubleReply>& f) {
    EXPECT_TRUE(until([&] { return f.ready(); })) << "the call never completed";
    return f.ready() ? f.get()
                     : Expected<Message<DoubleReply>>(make_error(PLR_ERR_STATE, "pending"));
  }
  // Records what arrives on `topic` for the test as "test:<topic> <value>".
  void listen(const std::string& topic) {
    ASSERT_TRUE(test->subscribe<Count>(topic, [topic](const Message<Count>& m) {
      note("test:" + topic + " " + std::to_string(m->value()));
    }));
  }

  std::unique_ptr<Context> test;
  std::unique_ptr<ContractHost> host;
};

std::vector<std::string> events(const std::string& prefix) {
  return Journal::get().with(prefix);
}

using Body = std::function<void(Session&)>;

struct Promise {
  const char* name;
  Body body;
};

// --- The promises --------------------------------------------------------------

const std::vector<Promise>& promises() {
  static const std::vector<Promise> all = {
      {"LifeCycleHooksRunInOrderWithTheParamsAndName",
       [](Session& r) {
         ASSERT_TRUE(r.host->add(probe_plugin(), "p", R"({"factor": 3})", {}));
         ASSERT_TRUE(r.host->configure("p"));
         ASSERT_TRUE(r.host->activate("p"));
         ASSERT_TRUE(r.host->deactivate("p"));
         ASSERT_TRUE(r.host->cleanup("p"));
         r.host->destroy("p");
         EXPECT_EQ(events("p:"),
                   (std::vector<std::string>{"p:configure {\"factor\":3}", "p:activate",
                                             "p:deactivate", "p:cleanup", "p:destroyed"}));
       }},
      {"AStepOutOfOrderIsRefusedAndChangesNothing",
       [](Session& r) {
         ASSERT_TRUE(r.host->add(probe_plugin(), "p", "{}", {}));
         const Status early = r.host->activate("p");
         ASSERT_FALSE(early);
         EXPECT_EQ(early.error().code, PLR_ERR_STATE) << early.error().message;
         EXPECT_EQ(early.error().message.find('\n'), std::string::npos);
         EXPECT_TRUE(r.host->configure("p"));
         EXPECT_FALSE(r.host->configure("p")) << "configured twice";
         EXPECT_TRUE(r.host->activate("p"));
         EXPECT_EQ(events("p:"), (std::vector<std::string>{"p:configure {}", "p:activate"}));
       }},
      {"AFailedConfigureKeepsNothingAndCanBeRetried",
       [](Session& r) {
         ASSERT_TRUE(r.host->add(probe_plugin(), "p", R"({"fail_configure_once": true})", {}));
         const Status failed = r.host->configure("p");
         ASSERT_FALSE(failed);
         EXPECT_EQ(failed.error().code, PLR_ERR_INVALID);
         EXPECT_NE(failed.error().message.find("first configure refused on purpose"),
                   std::string::npos)
             << failed.error().message;
         // Its services went with the failure, so the retry may provide them again.
         const Status again = r.host->configure("p");
         ASSERT_TRUE(again) << again.error().message;
         ASSERT_TRUE(r.host->activate("p"));
         auto reply = r.result(r.call("double", 4));
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 8);
       }},
      {"CleanupDropsWhatTheNodeRegistered",
       [](Session& r) {
         r.start("p");
         ASSERT_TRUE(r.host->deactivate("p"));
         ASSERT_TRUE(r.host->cleanup("p"));
         auto refused = r.call("double", 1);
         ASSERT_TRUE(refused.ready()) << "a call nobody can answer is refused at once";
         EXPECT_EQ(refused.get().error().code, PLR_ERR_UNAVAILABLE);
         ASSERT_TRUE(r.host->configure("p")) << "registering again after cleanup";
         ASSERT_TRUE(r.host->activate("p"));
         auto reply = r.result(r.call("double", 5));
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 10);
       }},
      {"OnlyAnActiveNodeReceivesMessagesAndRequests",
       [](Session& r) {
         ASSERT_TRUE(r.host->add(probe_plugin(), "p", "{}", {}));
         ASSERT_TRUE(r.host->configure("p"));
         r.publish("in", 1);
         auto refused = r.call("double", 1);
         ASSERT_TRUE(refused.ready());
         EXPECT_EQ(refused.get().error().code, PLR_ERR_UNAVAILABLE);
         r.settle();
         ASSERT_TRUE(r.host->activate("p"));
         r.settle();
         EXPECT_TRUE(events("p:in").empty()) << "a message sent before activation arrived";
         r.publish("in", 2);
         EXPECT_TRUE(r.until([] { return !events("p:in").empty(); }));
         r.settle();
         EXPECT_EQ(events("p:in"), (std::vector<std::string>{"p:in 2"}));
       }},
      {"WhatAnActiveNodeAcceptedReachesItBeforeItsDeactivateHook",
       [](Session& r) {
         r.start("p");
         for (int i = 1; i <= 5; ++i) r.publish("in", i);
         auto call = r.call("double", 21);
         ASSERT_TRUE(r.host->deactivate("p"));
         auto reply = r.result(call);
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 42);
         EXPECT_EQ(events("p:"), (std::vector<std::string>{"p:configure {}", "p:activate", "p:in 1",
                                                           "p:in 2", "p:in 3", "p:in 4", "p:in 5",
                                                           "p:double 21", "p:deactivate"}));
       }},
      {"ATopicCarriesEachMessageToEverySubscriberInOrder",
       [](Session& r) {
         r.start("a");
         r.start("b");
         r.listen("out");
         for (int i = 1; i <= 20; ++i) r.publish("in", i);
         EXPECT_TRUE(r.until([] { return events("test:out").size() == 40; }));
         std::vector<std::string> in_order;
         for (int i = 1; i <= 20; ++i) in_order.push_back(":in " + std::to_string(i));
         for (const std::string node : {"a", "b"}) {
           std::vector<std::string> seen;
           for (const auto& e : events(node + ":in")) seen.push_back(e.substr(node.size()));
           EXPECT_EQ(seen, in_order) << node;
         }
         EXPECT_EQ(events("test:out").front(), "test:out 2");
       }},
      {"AMessageThatFailsVerificationIsRejectedNotDelivered",
       [](Session& r) {
         r.start("p");
         const plr_host_api* api = r.host->test_api();
         std::uint64_t publisher = 0;
         ASSERT_EQ(api->advertise(api->ctx, "in", MessageTraits<Count>::type_id(),
                                  MessageTraits<Count>::schema_version, &publisher),
                   PLR_OK);
         std::uint8_t* data = nullptr;
         plr_msg* garbage = api->msg_alloc(api->ctx, 16, &data);
         ASSERT_NE(garbage, nullptr);
         std::fill(data, data + 16, std::uint8_t{0xff});
         ASSERT_EQ(api->publish(api->ctx, publisher, garbage, 0, 16), PLR_OK);
         EXPECT_TRUE(r.until([&] { return r.host->rejected() == 1; }));
         r.publish("in", 7);
         EXPECT_TRUE(r.until([] { return !events("p:in").empty(); }));
         EXPECT_EQ(events("p:in"), (std::vector<std::string>{"p:in 7"}));
       }},
      {"ATopicKeepsTheTypeItWasFirstUsedWith",
       [](Session& r) {
         r.start("p");
         auto wrong = r.test->advertise<DoubleRequest>("out");
         ASSERT_FALSE(wrong);
         EXPECT_EQ(wrong.error().code, PLR_ERR_INVALID);
         const Status sub =
             r.test->subscribe<DoubleReply>("in", [](const Message<DoubleReply>&) {});
         ASSERT_FALSE(sub);
         EXPECT_EQ(sub.error().code, PLR_ERR_INVALID);
       }},
      {"PublishAndCallTakeTheBufferEvenWhenTheyRefuse",
       [](Session& r) {
         const std::int64_t before = r.host->live_messages();
         const plr_host_api* api = r.host->test_api();
         std::uint8_t* data = nullptr;
         plr_msg* m = api->msg_alloc(api->ctx, 8, &data);
         EXPECT_NE(api->publish(api->ctx, 987654321, m, 0, 8), PLR_OK) << "an unknown publisher";
         m = api->msg_alloc(api->ctx, 8, &data);
         EXPECT_NE(api->publish(api->ctx, 987654321, m, 4, 8), PLR_OK) << "a range past the end";
         auto refused = r.call("nobody", 1);
         ASSERT_TRUE(refused.ready());
         EXPECT_EQ(refused.get().error().code, PLR_ERR_UNAVAILABLE);
         r.settle();
         EXPECT_EQ(r.host->live_messages(), before);
       }},
      {"ACallGetsItsReply",
       [](Session& r) {
         r.start("p", R"({"factor": 3})");
         auto reply = r.result(r.call("double", 14));
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 42);
       }},
      {"AProvidersErrorReachesTheCallerWithItsCodeAndText",
       [](Session& r) {
         r.start("p", R"({"fail_odd": true})");
         auto reply = r.result(r.call("double", 3));
         ASSERT_FALSE(reply);
         EXPECT_EQ(reply.error().code, PLR_ERR_INVALID);
         EXPECT_EQ(reply.error().message, "odd request 3");
       }},
      {"ACallOfTheWrongRequestTypeIsRefused",
       [](Session& r) {
         r.start("p");
         auto wrong = r.test->call<Count, DoubleReply>("double", count(1));
         ASSERT_TRUE(wrong.ready());
         EXPECT_EQ(wrong.get().error().code, PLR_ERR_INVALID);
         r.settle();
         EXPECT_TRUE(events("p:double").empty());
       }},
      {"ATimedOutCallCompletesOnceAndALateAnswerIsRefused",
       [](Session& r) {
         r.start("p");
         auto call = r.call("slow", 1, 20ms);
         auto reply = r.result(call);
         ASSERT_FALSE(reply);
         EXPECT_EQ(reply.error().code, PLR_ERR_TIMEOUT);
         EXPECT_NE(reply.error().message.find("slow"), std::string::npos)
             << "the timeout names the service: " << reply.error().message;
         ASSERT_TRUE(r.until([] { return Journal::get().has("p:holding"); }));
         r.publish("answer", 5);
         EXPECT_TRUE(r.until([] { return Journal::get().has("p:answer refused"); }));
         EXPECT_EQ(call.get().error().code, PLR_ERR_TIMEOUT) << "completed once";
       }},
      {"ACancelledCallCompletesOnceAndALateAnswerIsRefused",
       [](Session& r) {
         r.start("p");
         auto call = r.call("slow", 1);
         ASSERT_TRUE(r.until([] { return Journal::get().has("p:holding"); }));
         call.cancel();
         auto reply = r.result(call);
         ASSERT_FALSE(reply);
         EXPECT_EQ(reply.error().code, PLR_ERR_CANCELLED);
         r.publish("answer", 5);
         EXPECT_TRUE(r.until([] { return Journal::get().has("p:answer refused"); }));
       }},
      {"AHeldRequestIsAnsweredLater",
       [](Session& r) {
         r.start("p");
         auto call = r.call("slow", 1);
         ASSERT_TRUE(r.until([] { return Journal::get().has("p:holding"); }));
         EXPECT_FALSE(call.ready());
         r.publish("answer", 77);
         auto reply = r.result(call);
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 77);
         EXPECT_TRUE(Journal::get().has("p:answered"));
       }},
      {"AnAnswerMayComeFromAnotherThread",
       [](Session& r) {
         r.start("p");
         auto call = r.call("later", 4);
         r.settle();  // the request is delivered
         // The node's own thread answers: the call completes without the kernel's help.
         ASSERT_TRUE(call.wait_for(10s)) << "the answer from another thread never arrived";
         auto reply = call.get();
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 40);
       }},
      {"ARequestDroppedUnansweredFailsTheCall",
       [](Session& r) {
         r.start("p");
         auto reply = r.result(r.call("drop", 1));
         ASSERT_FALSE(reply);
         EXPECT_EQ(reply.error().code, PLR_ERR_INTERNAL);
         EXPECT_EQ(reply.error().message, "provider dropped the request unanswered");
       }},
      {"AProviderThatGoesAwayFailsTheCallsItHolds",
       [](Session& r) {
         r.start("p");
         auto call = r.call("slow", 1);
         ASSERT_TRUE(r.until([] { return Journal::get().has("p:holding"); }));
         r.host->destroy("p");
         auto reply = r.result(call);
         ASSERT_FALSE(reply);
         EXPECT_EQ(reply.error().code, PLR_ERR_UNAVAILABLE) << reply.error().message;
       }},
      {"OneServiceHasProvidersOfOneTypeAndTheFirstActiveAnswers",
       [](Session& r) {
         r.start("a", R"({"factor": 2})");
         // A second provider of the same types is what a hot swap needs.
         r.start("b", R"({"factor": 3})");
         auto reply = r.result(r.call("double", 1));
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 2) << "the first active provider answers";
         ASSERT_TRUE(r.host->deactivate("a"));
         reply = r.result(r.call("double", 1));
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 3);
         // Other message types, or the same node again, are refused.
         const Status other = r.test->provide<Count, DoubleReply>(
             "double",
             [](const Message<Count>&, flatbuffers::FlatBufferBuilder&) { return Status{}; });
         ASSERT_FALSE(other);
         EXPECT_EQ(other.error().code, PLR_ERR_INVALID);
         const auto same = [](const Message<DoubleRequest>&, flatbuffers::FlatBufferBuilder&) {
           return Status{};
         };
         ASSERT_TRUE((r.test->provide<DoubleRequest, DoubleReply>("mine", same)));
         const Status twice = r.test->provide<DoubleRequest, DoubleReply>("mine", same);
         ASSERT_FALSE(twice);
         EXPECT_EQ(twice.error().code, PLR_ERR_INVALID);
       }},
      {"RemapsRenameTopicsAndServices",
       [](Session& r) {
         r.start("p", "{}", {{"in", "bus/in"}, {"out", "bus/out"}, {"double", "bus/double"}});
         r.listen("bus/out");
         r.publish("bus/in", 1);
         EXPECT_TRUE(r.until([] { return Journal::get().has("test:bus/out 2"); }));
         auto reply = r.result(r.call("bus/double", 6));
         ASSERT_TRUE(reply) << reply.error().message;
         EXPECT_EQ(reply.value()->value(), 12);
         auto unmapped = r.call("double", 6);
         ASSERT_TRUE(unmapped.ready()) << "the node's own name is not on the bus";
         EXPECT_EQ(unmapped.get().error().code, PLR_ERR_UNAVAILABLE);
       }},
      {"AQuickServiceAnswersLikeAnyOther",
       [](Session& r) {
         r.start("p", R"({"quick": true})");
         std::vector<Future<DoubleReply>> calls;
         for (int i = 0; i < 10; ++i) calls.push_back(r.call("double", i));
         for (int i = 0; i < 10; ++i) {
           auto reply = r.result(calls[static_cast<std::size_t>(i)]);
           ASSERT_TRUE(reply) << reply.error().message;
           EXPECT_EQ(reply.value()->value(), 2 * i);
         }
       }},
      {"ACallbackThatThrowsIsContained",
       [](Session& r) {
         r.start("p", R"({"throw_on": 13})");
         r.publish("in", 13);
         r.publish("in", 14);
         EXPECT_TRUE(r.until([] { return Journal::get().has("p:in 14"); }));
         auto reply = r.result(r.call("double", 2));
         ASSERT_TRUE(reply) << reply.error().message;
       }},
      {"NothingLeaksOnceTheNodesAreGone",
       [](Session& r) {
         const std::int64_t before = r.host->live_messages();
         r.start("p");
         r.listen("out");
         for (int i = 0; i < 10; ++i) r.publish("in", i);
         auto held = r.call("slow", 1);
         EXPECT_TRUE(r.result(r.call("double", 1)));
         ASSERT_TRUE(r.until([] { return events("test:out").size() == 10; }));
         r.host->destroy("p");
         (void)r.result(held);
         r.settle();
         EXPECT_EQ(r.host->live_messages(), before);
       }},
  };
  return all;
}

class PromiseTest : public ::testing::Test {
 public:
  PromiseTest(Body body, ContractHostFactory make)
      : body_(std::move(body)), make_(std::move(make)) {}
  void TestBody() override {
    Session session(make_);
    body_(session);
  }

 private:
  Body body_;
  ContractHostFactory make_;
};

}  // namespace

void register_host_contract_tests(const std::string& suite, ContractHostFactory make) {
  for (const Promise& p : promises()) {
    ::testing::RegisterTest(
        suite.c_str(), p.name, nullptr, nullptr, __FILE__, __LINE__,
        [body = p.body, make]() -> ::testing::Test* { return new PromiseTest(body, make); });
  }
}

}  // namespace plr::testing
