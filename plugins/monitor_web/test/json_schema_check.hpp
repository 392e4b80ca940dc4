// Checks a JSON value against a JSON Schema, for the keywords Foxglove's
// message schemas use: type, properties, items, minimum, maximum, oneOf,
// const, contentEncoding (base64), and the annotations title, description
// and $comment. A keyword it does not know is itself a violation, so a
// schema it cannot judge never passes. With `complete`, it is stricter than
// JSON Schema: every listed property must be present and no other (a
// misspelt field would otherwise be ignored by the 3D panel, silently).
#pragma once

#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

namespace plr::monitor_web::testing {

// The first violation, "<path>: <what>", or "" when `value` conforms.
inline std::string schema_violation(const nlohmann::json& schema, const nlohmann::json& value,
                                    bool complete, const std::string& path = "$") {
  using nlohmann::json;
  if (!schema.is_object()) return path + ": the schema is not an object";
  for (const auto& [key, rule] : schema.items()) {
    if (key == "title" || key == "description" || key == "$comment") continue;
    if (key == "type") {
      const std::string t = rule.get<std::string>();
      const bool ok = t == "object"    ? value.is_object()
                      : t == "array"   ? value.is_array()
                      : t == "string"  ? value.is_string()
                      : t == "boolean" ? value.is_boolean()
                      : t == "number"  ? value.is_number()
                      : t == "integer"
                          ? value.is_number_integer() ||
                                (value.is_number_float() &&
                                 std::floor(value.get<double>()) == value.get<double>())
                          : false;
      if (!ok) return path + ": expected " + t + ", got " + value.type_name() + " " + value.dump();
    } else if (key == "properties") {
      if (!value.is_object()) continue;  // "type" says what it must be
      for (const auto& [name, sub] : rule.items()) {
        if (!value.contains(name)) {
          if (complete) return path + ": missing '" + name + "'";
          continue;
        }
        auto v = schema_violation(sub, value.at(name), complete, path + "." + name);
        if (!v.empty()) return v;
      }
      if (complete)
        for (const auto& [name, v] : value.items())
          if (!rule.contains(name)) return path + ": '" + name + "' is not in the schema";
    } else if (key == "items") {
      if (!value.is_array()) continue;
      for (std::size_t i = 0; i < value.size(); ++i) {
        auto v = schema_violation(rule, value[i], complete, path + "[" + std::to_string(i) + "]");
        if (!v.empty()) return v;
      }
    } else if (key == "minimum" || key == "maximum") {
      if (!value.is_number()) continue;
      const double x = value.get<double>(), bound = rule.get<double>();
      if (key == "minimum" ? x < bound : x > bound)
        return path + ": " + value.dump() + " is beyond " + key + " " + rule.dump();
    } else if (key == "const") {
      if (value != rule) return path + ": " + value.dump() + " is not " + rule.dump();
    } else if (key == "oneOf") {
      int matches = 0;
      for (const auto& sub : rule)
        if (schema_violation(sub, value, complete, path).empty()) ++matches;
      if (matches != 1)
        return path + ": " + value.dump() + " matches " + std::to_string(matches) +
               " of oneOf, not 1";
    } else if (key == "contentEncoding") {
      if (rule != "base64") return path + ": contentEncoding " + rule.dump() + " not understood";
      if (!value.is_string()) continue;
      const auto& s = value.get_ref<const std::string&>();
      if (s.size() % 4 != 0 || s.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstu"
                                                   "vwxyz0123456789+/=") != std::string::npos)
        return path + ": not base64";
    } else {
      return path + ": schema keyword '" + key + "' is not understood by this check";
    }
  }
  return {};
}

}  // namespace plr::monitor_web::testing
