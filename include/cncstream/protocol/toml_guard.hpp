#pragma once
// Text that Debian bookworm's toml++ 3.3 would misbehave on (an assertion, or
// undefined behaviour in a release build) instead of refusing, refused first
// with its line. Every TOML file from outside (the daemon's configuration,
// firmware profiles) goes through it before toml::parse.
#include <string>
#include <string_view>

namespace cncstream::protocol {

// Throws std::invalid_argument "<source>:<line>: <why>".
void check_toml_text(std::string_view text, const std::string& source);

}  // namespace cncstream::protocol
