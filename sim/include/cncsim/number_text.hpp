#pragma once
// Numbers in the simulator's options and files ("LINE:VALUE", "X,Y,Z", a
// tool number). Each field must be one number and nothing else, in range:
// sscanf's %d/%zu/%lf, used before, are undefined or silently wrong on values
// out of range (cert-err34-c). Blanks around a field and a leading '+' are
// taken, as sscanf took them.
#include <charconv>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "cncstream/geometry/vec3.hpp"

namespace cncsim {

template <typename T>
std::optional<T> number_from(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  if (text.size() > 1 && text.front() == '+' && text[1] != '-') text.remove_prefix(1);
  T value{};
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, value);
  if (r.ec != std::errc() || r.ptr != end) return std::nullopt;
  return value;
}

// "X,Y,Z".
inline std::optional<cncstream::geometry::Vec3> vec3_from(std::string_view text) {
  const auto c1 = text.find(',');
  const auto c2 = c1 == std::string_view::npos ? c1 : text.find(',', c1 + 1);
  if (c2 == std::string_view::npos) return std::nullopt;
  const auto x = number_from<double>(text.substr(0, c1));
  const auto y = number_from<double>(text.substr(c1 + 1, c2 - c1 - 1));
  const auto z = number_from<double>(text.substr(c2 + 1));
  if (!x || !y || !z) return std::nullopt;
  return cncstream::geometry::Vec3{*x, *y, *z};
}

// "LINE:VALUE" for the per-line faults (--error-at, --alarm-at, --stall-at, in
// cncsim's options and cncstream's --sim-*): LINE >= 1; an integer VALUE (an
// error or alarm code) must be a whole number T holds.
template <typename T>
void parse_line_faults(const std::vector<std::string>& specs, const char* flag, std::map<std::size_t, T>& out) {
  for (const std::string& s : specs) {
    const std::string_view text(s);
    const auto colon = text.find(':');
    const auto line = colon == std::string_view::npos ? std::nullopt : number_from<std::size_t>(text.substr(0, colon));
    const auto value = colon == std::string_view::npos ? std::nullopt : number_from<double>(text.substr(colon + 1));
    bool fits = value.has_value();
    if constexpr (std::is_integral_v<T>)
      fits = fits && *value == std::floor(*value) && *value >= static_cast<double>(std::numeric_limits<T>::min()) &&
             *value <= static_cast<double>(std::numeric_limits<T>::max());
    if (!line || *line == 0 || !fits)
      throw std::invalid_argument(std::string(flag) + " '" + s + "': expected LINE:VALUE with LINE >= 1" +
                                  (std::is_integral_v<T> ? " and a whole VALUE" : ""));
    out[*line] = static_cast<T>(*value);
  }
}

}  // namespace cncsim
