// An endpoint the test drives: a name and a thread of its own (a node
// without a plug-in). Shared by the kernel, transport and remote tests.
#pragma once

#include "bus.hpp"

#include <string>

namespace plr::kernel::testing {

class TestEndpoint final : public Endpoint {
 public:
  explicit TestEndpoint(std::string name = "test") : name_(std::move(name)), executor_(name_) {}
  Executor& executor() override { return executor_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  std::string name_;
  Executor executor_;
};

}  // namespace plr::kernel::testing
