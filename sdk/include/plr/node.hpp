// The base class of every node. The life cycle is public and non-virtual: it
// checks the state once, here, and calls the protected on_* hooks a plug-in
// implements (unconfigured -> configured -> active -> configured -> unconfigured).
#pragma once

#include <plr/context.hpp>
#include <plr/expected.hpp>

#include <exception>

namespace plr {

enum class NodeState { Unconfigured, Configured, Active };

inline const char* to_string(NodeState s) {
  switch (s) {
    case NodeState::Unconfigured:
      return "unconfigured";
    case NodeState::Configured:
      return "configured";
    case NodeState::Active:
      return "active";
  }
  return "unknown";
}

class Node {
 public:
  explicit Node(const plr_host_api* host) : ctx_(host) {}
  virtual ~Node() = default;
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  Status configure() {
    return transition("configure", NodeState::Unconfigured, NodeState::Configured,
                      &Node::on_configure);
  }
  Status activate() {
    return transition("activate", NodeState::Configured, NodeState::Active, &Node::on_activate);
  }
  // Deactivating a node that is not active is a no-op, so shutdown paths can call it freely.
  Status deactivate() {
    if (state_ != NodeState::Active) return {};
    return transition("deactivate", NodeState::Active, NodeState::Configured, &Node::on_deactivate);
  }
  Status cleanup() {
    return transition("cleanup", NodeState::Configured, NodeState::Unconfigured, &Node::on_cleanup);
  }

  NodeState state() const { return state_; }

 protected:
  virtual Status on_configure() { return {}; }
  virtual Status on_activate() { return {}; }
  virtual Status on_deactivate() { return {}; }
  virtual Status on_cleanup() { return {}; }

  Context& ctx() { return ctx_; }
  const Params& params() const { return ctx_.params(); }
  const Logger& log() const { return ctx_.log(); }

 private:
  Status transition(const char* what, NodeState from, NodeState to, Status (Node::*hook)()) {
    if (state_ != from)
      return make_error(PLR_ERR_STATE, std::string(what) + ": node is " + to_string(state_) +
                                           ", needs " + to_string(from));
    Status result;
    try {
      result = (this->*hook)();
    } catch (const std::exception& e) {
      result = make_error(PLR_ERR_INVALID, e.what());
    }
    if (result) state_ = to;
    return result;
  }

  Context ctx_;
  NodeState state_ = NodeState::Unconfigured;
};

}  // namespace plr
