// A recorded set of planning queries, each with the world it was asked on
// (a benchmark's input: bench_unload records the queries that spent their
// whole budget, bench_planner reads them back). The file is the queries'
// PlanRequest buffers (sdk/schemas/plan.fbs) one after another, each in
// PLR's frame (plr/frame.hpp: size, payload, CRC-32).
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <vector>

#include "plr/planning/plan_query.hpp"

namespace plr::planning {

struct RecordedQuery {
  PlanQuery query;
  sim::World world;  // without the query's ignored boxes (they travel so)
};

// One query as a framed PlanRequest, to append to a query-set file.
std::vector<std::uint8_t> frame_query(const PlanQuery& query, const sim::World& world);

// The frames written atomically as one file.
plr::Status save_query_set(const std::vector<std::vector<std::uint8_t>>& frames,
                           const std::filesystem::path& file);

// Every query of a file; an error names the file and the first bad frame
// ("set.bin: query 3: PlanRequest.start: needs 8 joint values, got 7").
plr::Expected<std::vector<RecordedQuery>> load_query_set(const std::filesystem::path& file);

}  // namespace plr::planning
