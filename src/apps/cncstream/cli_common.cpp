#include "cli_common.hpp"

#include <charconv>
#include <stdexcept>

namespace cncstream::app {

void add_part_options(CLI::App* sub, PartOptions& o) {
  sub->add_option("--units", o.units, "Units of the STL: mm, in or m")
      ->check(CLI::IsMember({"mm", "in", "m"}))
      ->capture_default_str();
  sub->add_option("--scale", o.scale, "Extra scale factor applied after the units")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--max-part-size", o.max_part_mm, "Refuse parts larger than this on any axis, mm (wrong units)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

jobs::PartSource part_source(const PartOptions& o) {
  jobs::PartSource p;
  p.stl = o.stl;
  p.units = geometry::parse_length_unit(o.units);
  p.scale = o.scale;
  p.max_extent_mm = o.max_part_mm;
  return p;
}

std::array<double, 4> parse_bounds(const std::string& text) {
  std::array<double, 4> v{};
  std::size_t pos = 0;
  for (int k = 0; k < 4; ++k) {
    const std::size_t end = k < 3 ? text.find(',', pos) : text.size();
    if (end == std::string::npos)
      throw std::invalid_argument("--bounds '" + text + "': expected X0,Y0,X1,Y1");
    const std::string part = text.substr(pos, end - pos);
    auto [p, ec] = std::from_chars(part.data(), part.data() + part.size(), v[k]);
    if (part.empty() || ec != std::errc() || p != part.data() + part.size())
      throw std::invalid_argument("--bounds '" + text + "': '" + part + "' is not a number");
    pos = end + 1;
  }
  if (!(v[2] > v[0]) || !(v[3] > v[1]))
    throw std::invalid_argument("--bounds '" + text + "': X1 must exceed X0 and Y1 must exceed Y0");
  return v;
}

}  // namespace cncstream::app
