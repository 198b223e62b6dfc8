#pragma once
// Names compare case-insensitively across the tool library, the material
// table and the imports (ASCII: the formats' keywords and users' names).
#include <cctype>
#include <string>
#include <string_view>

namespace cncstream::tooling::detail_lower_case {

inline std::string lower(std::string_view s) {
  std::string o(s);
  for (char& c : o) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return o;
}

}  // namespace cncstream::tooling::detail_lower_case
