#pragma once
// The tooling room's TOML files (the tool library, the material table): text
// from outside goes through the project's guard for what toml++ 3.3
// misbehaves on, then toml++; a syntax error names the file, line and column.
#define TOML_HEADER_ONLY 1
#define TOML_EXCEPTIONS 1
#include <fmt/format.h>
#include <toml++/toml.h>

#include <stdexcept>
#include <string>
#include <string_view>

#include "cncstream/protocol/toml_guard.hpp"

namespace cncstream::tooling::detail_toml_read {

inline toml::table parse_toml(std::string_view text, const std::string& source) {
  protocol::check_toml_text(text, source);
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}:{}:{}: {}", source, e.source().begin.line, e.source().begin.column,
                                            e.description()));
  }
}

}  // namespace cncstream::tooling::detail_toml_read
