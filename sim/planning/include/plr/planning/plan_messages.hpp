// PlanRequest / PlanResponse (sdk/schemas/plan.fbs) <-> plan types: how a
// query crosses the bus to the `plan` service and its answer comes back.
#pragma once

#include <plr/expected.hpp>

#include <memory>
#include <string>
#include <vector>

#include "plr/planning/plan_query.hpp"

namespace plr::msg {
struct PlanRequest;
struct PlanResponse;
}  // namespace plr::msg
namespace flatbuffers {
class FlatBufferBuilder;
}
namespace octomap {
class OcTree;
}

namespace plr::planning {

struct DecodedPlanRequest {
  PlanQuery query;
  sim::World world;
  std::shared_ptr<const octomap::OcTree> octree;  // null: build the trailer shell
};

// Checks every field of a verified message; the error names the bad one, e.g.
// "PlanRequest.start: needs 8 joint values, got 7".
plr::Expected<DecodedPlanRequest> decode_plan_request(const plr::msg::PlanRequest& request);

// Finishes `out` with a PlanResponse; the trajectory is sampled every
// `sample_dt` seconds (plus its end).
void encode_plan_response(const PlanResult& result, const std::string& planner, double sample_dt,
                          flatbuffers::FlatBufferBuilder& out);

// The caller's side. A query's ignored boxes travel by leaving them out of
// the world (held boxes stay: they are part of the arm).
void encode_plan_request(const PlanQuery& query, const sim::World& world,
                         flatbuffers::FlatBufferBuilder& out);

struct TimedPoint {
  double time_s = 0.0;
  JointVector position = JointVector::Zero();
  JointVector velocity = JointVector::Zero();
};

struct DecodedPlanResponse {
  PlanStatus status = PlanStatus::kInvalidRequest;
  std::string message;
  std::string planner;
  std::vector<TimedPoint> points;  // the trajectory as sampled by the planner node
  PlanStats stats;
};

// Checks every field of a verified message, like decode_plan_request().
plr::Expected<DecodedPlanResponse> decode_plan_response(const plr::msg::PlanResponse& response);

}  // namespace plr::planning
