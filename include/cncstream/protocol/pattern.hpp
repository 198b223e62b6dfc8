#pragma once
// Regular-expression helpers for firmware profiles (banner and version patterns).
// All use of <regex> lives in one translation unit: GCC 12 reports a false
// -Wmaybe-uninitialized inside libstdc++'s regex compiler under -O2 + ASan.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::protocol {

// True when any ECMAScript pattern matches somewhere in `text`.
bool matches_any_pattern(const std::vector<std::string>& patterns, std::string_view text);

// The compiler's complaint about `pattern`, or nothing when it is a valid ECMAScript regex.
std::optional<std::string> pattern_error(const std::string& pattern);

}  // namespace cncstream::protocol
