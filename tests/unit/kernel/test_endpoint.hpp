// An endpoint the test drives: a name and a thread of its own (a node
// without a plug-in). Shared by the kernel's tests and the planner's swap test.
#pragma once

#include "bus.hpp"

#include <string>

namespace plr::kernel::testing {

class TestEndpoint final : public Endpoint {
 public:
  explicit TestEndpoint(std::string name = "test") : name_(std::move(name)), node_thread_(name_) {}
  NodeThread& node_thread() override { return node_thread_; }
  // The old name, still called by tests/unit/planner/swap_under_load_test.cpp
  // (another team's folder); goes once that file says node_thread().
  NodeThread& executor() { return node_thread_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  std::string name_;
  NodeThread node_thread_;
};

}  // namespace plr::kernel::testing
