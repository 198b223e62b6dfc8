#include "cncstream/jobs/size_limits.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace cncstream::jobs {

namespace {

std::string human_bytes(double b) {
  char buf[48];
  if (b >= 1e9) std::snprintf(buf, sizeof buf, "%.1f GB", b / 1e9);
  else std::snprintf(buf, sizeof buf, "%.0f MB", b / 1e6);
  return buf;
}

}  // namespace

void check_part_size(const Box3& bounds, const std::string& source, double limit_mm) {
  const Vec3 size = bounds.hi - bounds.lo;
  const double largest = std::max({size.x, size.y, size.z});
  if (std::isfinite(largest) && largest <= limit_mm) return;
  char buf[400];
  if (!std::isfinite(largest)) {
    std::snprintf(buf, sizeof buf, "%s: the part's coordinates are not finite numbers", source.c_str());
    throw std::invalid_argument(buf);
  }
  // The power of ten that brings it back under a metre says what went wrong.
  const double k = std::pow(10.0, -std::ceil(std::log10(largest / 1000.0)));
  char hint[160];
  if (largest > 2 * limit_mm)
    std::snprintf(hint, sizeof hint,
                  "its coordinates are probably in another unit: with --scale %g it would be %.1f mm long (or "
                  "--units in / m)",
                  k, largest * k);
  else
    std::snprintf(hint, sizeof hint, "if it really is this large, raise --max-part-size");
  std::snprintf(buf, sizeof buf, "%s: the part is %.1f x %.1f x %.1f mm, larger than the %.0f mm a part may be; %s",
                source.c_str(), size.x, size.y, size.z, limit_mm, hint);
  throw std::invalid_argument(buf);
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
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "%s: %.0f x %.0f nodes at %g mm (%.3g nodes) would need about %s, more than the %s this job may use; "
                "use a coarser step or a smaller region",
                what.c_str(), std::ceil(nx), std::ceil(ny), step_mm, nodes, human_bytes(bytes).c_str(),
                human_bytes(static_cast<double>(budget)).c_str());
  throw std::invalid_argument(buf);
}

}  // namespace cncstream::jobs
