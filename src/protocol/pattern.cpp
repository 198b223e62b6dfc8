#include "cncstream/protocol/pattern.hpp"

#if defined(__GNUC__) && !defined(__clang__)
// False positive in libstdc++ 12 (std::function move inside _NFA) at -O2 with sanitizers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <regex>

namespace cncstream::protocol {

bool matches_any_pattern(const std::vector<std::string>& patterns, std::string_view text) {
  for (const auto& p : patterns)
    if (std::regex_search(text.begin(), text.end(), std::regex(p))) return true;
  return false;
}

std::optional<std::string> pattern_error(const std::string& pattern) {
  try {
    std::regex re(pattern);
  } catch (const std::regex_error& e) {
    return std::string(e.what());
  }
  return std::nullopt;
}

}  // namespace cncstream::protocol
