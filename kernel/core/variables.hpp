// `${name}` placeholders in node parameters, filled in by the kernel before
// nodes see them: report_dir (plr run --report), config_dir, run_id.
#pragma once

#include "pipeline_config.hpp"

#include <plr/expected.hpp>

#include <map>
#include <string>

namespace plr::kernel {

// Replaces every `${name}` in string parameters; an unknown name is an error
// naming the node and the parameter.
Status substitute_variables(PipelineConfig& config,
                            const std::map<std::string, std::string>& values);

}  // namespace plr::kernel
