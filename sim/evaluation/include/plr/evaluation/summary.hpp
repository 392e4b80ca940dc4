// The evaluation's figures from its runs' results: per environment and
// method the mean unloading curve with its standard error, the paper's
// Table I (planner queries per mode) and Table II (picks and sweeps), and
// findings computed from them (who beats whom, where, by how many standard
// errors). report.json is this object; report.html and the plots are drawn
// from it alone.
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

#include "plr/evaluation/settings.hpp"

namespace plr::evaluation {

// Points of the common time grid the curves are averaged on (0 .. horizon).
inline constexpr int kGridPoints = 121;

// Boxes unloaded by robot time t on a run's curve ([[t, boxes], ...] in
// time order): the last point at or before t.
double boxes_at(const nlohmann::json& curve, double t);

// `runs`: the result objects of run_one (or of a failed run). `quick` is
// only recorded.
nlohmann::json summarize(const EvaluationSettings& settings,
                         const std::vector<nlohmann::json>& runs, bool quick);

}  // namespace plr::evaluation
