// Node parameters from the pipeline config, with typed access and clear errors.
#pragma once

#include <nlohmann/json.hpp>

#include <initializer_list>
#include <stdexcept>
#include <string>
#include <string_view>

namespace plr {

// Thrown by Params on a missing, mistyped or unknown key; the life cycle turns
// it into a failed configure() with this message.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Params {
 public:
  Params() = default;
  explicit Params(nlohmann::json values) : values_(std::move(values)) {}

  bool has(std::string_view key) const { return values_.contains(key); }

  template <class T>
  T get(std::string_view key, T fallback) const {
    if (!has(key)) return fallback;
    return convert<T>(key);
  }

  template <class T>
  T require(std::string_view key) const {
    if (!has(key)) throw ParamError("param '" + std::string(key) + "': required but missing");
    return convert<T>(key);
  }

  // Refuses keys the node does not know, so a typo never goes unnoticed.
  void allow_only(std::initializer_list<std::string_view> known) const {
    for (const auto& [key, value] : values_.items()) {
      bool found = false;
      for (auto k : known) found = found || k == key;
      if (!found) throw ParamError("param '" + key + "': unknown parameter");
    }
  }

  const nlohmann::json& json() const { return values_; }

 private:
  template <class T>
  T convert(std::string_view key) const {
    const auto& v = values_.at(std::string(key));
    try {
      if constexpr (std::is_same_v<T, bool>) {
        if (!v.is_boolean()) throw ParamError("");
      } else if constexpr (std::is_arithmetic_v<T>) {
        if (!v.is_number()) throw ParamError("");
        if constexpr (std::is_unsigned_v<T>) {
          if (v.get<double>() < 0) throw ParamError("");
        }
      } else if constexpr (std::is_same_v<T, std::string>) {
        if (!v.is_string()) throw ParamError("");
      }
      return v.get<T>();
    } catch (const std::exception&) {
      throw ParamError("param '" + std::string(key) + "': expected " + type_name<T>() + ", got " +
                       v.dump());
    }
  }

  template <class T>
  static std::string type_name() {
    if constexpr (std::is_same_v<T, bool>)
      return "a boolean";
    else if constexpr (std::is_unsigned_v<T>)
      return "a non-negative number";
    else if constexpr (std::is_arithmetic_v<T>)
      return "a number";
    else if constexpr (std::is_same_v<T, std::string>)
      return "a string";
    else
      return "a value of another type";
  }

  nlohmann::json values_ = nlohmann::json::object();
};

}  // namespace plr
