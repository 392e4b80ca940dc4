#include "variables.hpp"

#include <fmt/format.h>

namespace plr::kernel {

namespace {

Status substitute(nlohmann::json& value, const std::map<std::string, std::string>& values,
                  const std::string& where) {
  if (value.is_object() || value.is_array()) {
    for (auto it = value.begin(); it != value.end(); ++it) {
      const auto key = value.is_object() ? where + "." + it.key() : where;
      if (auto s = substitute(*it, values, key); !s) return s;
    }
    return {};
  }
  if (!value.is_string()) return {};
  std::string text = value.get<std::string>();
  for (std::size_t at = text.find("${"); at != std::string::npos; at = text.find("${", at)) {
    const auto end = text.find('}', at);
    if (end == std::string::npos) break;
    const auto name = text.substr(at + 2, end - at - 2);
    auto it = values.find(name);
    if (it == values.end())
      return make_error(PLR_ERR_INVALID,
                        fmt::format("{}: unknown variable '${{{}}}'", where, name));
    text.replace(at, end - at + 1, it->second);
    at += it->second.size();
  }
  value = text;
  return {};
}

}  // namespace

Status substitute_variables(PipelineConfig& config,
                            const std::map<std::string, std::string>& values) {
  for (auto& node : config.nodes)
    if (auto s = substitute(node.params, values,
                            fmt::format("{}: nodes.{}.params", node.where.str(), node.name));
        !s)
      return s;
  return {};
}

}  // namespace plr::kernel
