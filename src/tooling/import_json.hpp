#pragma once
// Reading the JSON tool formats (Fusion 360, FreeCAD): errors name the file
// and the JSON pointer of the value, or the byte of a syntax error.
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace cncstream::tooling::detail_import_json {

inline nlohmann::json parse_json(std::string_view text, const std::string& source) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}: byte {}: not valid JSON ({})", source, e.byte, e.what()));
  }
}

struct JsonPlace {
  std::string source;
  std::string pointer;  // "/data/3/geometry"

  JsonPlace at(std::string_view key) const { return {source, fmt::format("{}/{}", pointer, key)}; }
  JsonPlace at(std::size_t index) const { return {source, fmt::format("{}/{}", pointer, index)}; }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument(fmt::format("{}: {}: {}", source, pointer.empty() ? "/" : pointer, what));
  }
  std::optional<std::string> str(const nlohmann::json& j, const char* key) const {
    if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
    if (!j.at(key).is_string()) at(key).fail(fmt::format("expected a string, got {}", j.at(key).type_name()));
    return j.at(key).get<std::string>();
  }
  std::optional<double> num(const nlohmann::json& j, const char* key) const {
    if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
    if (!j.at(key).is_number()) at(key).fail(fmt::format("expected a number, got {}", j.at(key).type_name()));
    return j.at(key).get<double>();
  }
};

}  // namespace cncstream::tooling::detail_import_json
