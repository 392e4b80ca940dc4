// The learning curve: held-out validation accuracy against the labelled
// training states after each DAgger iteration, beside the cross-validated
// accuracy and the majority class's share (what a model must beat), as an
// SVG line chart.
#pragma once

#include <string>
#include <vector>

#include "plr/chooser/training/data_set.hpp"

namespace plr::chooser {

std::string curve_svg(const std::vector<IterationRecord>& iterations);

}  // namespace plr::chooser
