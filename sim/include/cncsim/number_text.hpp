#pragma once
// Numbers in the simulator's options and files ("LINE:VALUE", "X,Y,Z", a
// tool number). Each field must be one number and nothing else, in range:
// sscanf's %d/%zu/%lf, used before, are undefined or silently wrong on values
// out of range (cert-err34-c). Blanks around a field and a leading '+' are
// taken, as sscanf took them.
#include <charconv>
#include <cstddef>
#include <optional>
#include <string_view>
#include <system_error>

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
inline std::optional<cncstream::Vec3> vec3_from(std::string_view text) {
  const auto c1 = text.find(',');
  const auto c2 = c1 == std::string_view::npos ? c1 : text.find(',', c1 + 1);
  if (c2 == std::string_view::npos) return std::nullopt;
  const auto x = number_from<double>(text.substr(0, c1));
  const auto y = number_from<double>(text.substr(c1 + 1, c2 - c1 - 1));
  const auto z = number_from<double>(text.substr(c2 + 1));
  if (!x || !y || !z) return std::nullopt;
  return cncstream::Vec3{*x, *y, *z};
}

}  // namespace cncsim
