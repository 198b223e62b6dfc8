#include "cncstream/jobs/size_limits.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cncstream::jobs {

namespace {

std::string human_bytes(double b) {
  return b >= 1e9 ? fmt::format("{:.1f} GB", b / 1e9) : fmt::format("{:.0f} MB", b / 1e6);
}

}  // namespace

void check_part_size(const geometry::Box3& bounds, const std::string& source, double limit_mm) {
  const geometry::Vec3 size = bounds.hi - bounds.lo;
  const double largest = std::max({size.x, size.y, size.z});
  if (std::isfinite(largest) && largest <= limit_mm) return;
  if (!std::isfinite(largest))
    throw std::invalid_argument(fmt::format("{}: the part's coordinates are not finite numbers", source));
  // The power of ten that brings it back under a metre says what went wrong.
  const double k = std::pow(10.0, -std::ceil(std::log10(largest / 1000.0)));
  const std::string hint =
      largest > 2 * limit_mm
          ? fmt::format("its coordinates are probably in another unit: with --scale {:g} it would be {:.1f} mm long "
                        "(or --units in / m)",
                        k, largest * k)
          : std::string("if it really is this large, raise --max-part-size");
  throw std::invalid_argument(fmt::format("{}: the part is {:.1f} x {:.1f} x {:.1f} mm, larger than the {:.0f} mm a "
                                          "part may be; {}",
                                          source, size.x, size.y, size.z, limit_mm, hint));
}

std::string units_warning(const geometry::Box3& bounds, geometry::LengthUnit units, double cutter_diameter, const std::string& source) {
  if (bounds.empty()) return {};
  const geometry::Vec3 size = bounds.hi - bounds.lo;
  const double largest = std::max({size.x, size.y, size.z});
  if (!std::isfinite(largest) || !(largest > 0)) return {};
  // A part a router makes is rarely under 10 mm; under the cutter's own
  // width it cannot be machined at all. Read in another unit, it would be
  // this long: the candidates that land between 10 mm and 3 m.
  const bool tiny = largest < 10, under_cutter = largest < cutter_diameter;
  if (!tiny && !under_cutter) return {};
  const double to_mm = geometry::unit_to_mm(units);
  std::string hint;
  for (geometry::LengthUnit u : {geometry::LengthUnit::Inch, geometry::LengthUnit::Metre}) {
    if (u == units) continue;
    const double would = largest / to_mm * geometry::unit_to_mm(u);
    if (would < 10 || would > 3000) continue;
    hint += fmt::format("{}--units {} ({:.0f} mm)", hint.empty() ? "" : " or ", u == geometry::LengthUnit::Inch ? "in" : "m", would);
  }
  const std::string why = under_cutter ? fmt::format("smaller than the {:g} mm cutter", cutter_diameter)
                                       : std::string("only a few millimetres");
  return fmt::format("{}: the part is {:.3g} x {:.3g} x {:.3g} mm, {}{}", source, size.x, size.y, size.z, why,
                     hint.empty() ? std::string("; check its units") : "; were its numbers meant as " + hint + "?");
}

std::size_t memory_budget_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return std::size_t{4} << 30;  // unknown: 4 GiB
  return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page) / 2;
}

void check_grid_memory(double nx, double ny, double bytes_per_node, double step_mm, const std::string& what,
                       std::size_t budget) {
  if (budget == 0) budget = memory_budget_bytes();
  const double nodes = std::ceil(nx) * std::ceil(ny);
  const double bytes = nodes * bytes_per_node;
  if (std::isfinite(bytes) && bytes <= static_cast<double>(budget)) return;
  throw std::invalid_argument(
      fmt::format("{}: {:.0f} x {:.0f} nodes at {:g} mm ({:.3g} nodes) would need about {}, more than the {} this job "
                  "may use; use a coarser step or a smaller region",
                  what, std::ceil(nx), std::ceil(ny), step_mm, nodes, human_bytes(bytes),
                  human_bytes(static_cast<double>(budget))));
}

}  // namespace cncstream::jobs
