// Z-level roughing to G-code; see roughing_program.hpp.
#include "cncstream/gcode/roughing_program.hpp"

#include <cmath>
#include <stdexcept>

#include "cncstream/gcode/arc_fit.hpp"

namespace cncstream {

void write_roughing(GcodeWriter& w, const cam::RoughingPath& path, const geometry::Vec3& offset, const MachiningParams& p,
                    ProgramStats& st) {
  // Feeds are written with one decimal: below 0.1 mm/min would print as F0.
  if (!(p.feed >= 0.1) || !(p.plunge_feed >= 0.1) || !std::isfinite(p.feed) || !std::isfinite(p.plunge_feed))
    throw std::invalid_argument("feed " + format_gcode_number(p.feed, 6) + " and plunge feed " +
                                format_gcode_number(p.plunge_feed, 6) + " mm/min must each be at least 0.1");
  bool any = false;
  for (const auto& lv : path.levels)
    for (const auto& ps : lv.passes) any |= !ps.points.empty();
  if (!any) throw std::invalid_argument("roughing path is empty");
  // Z rounded up to the output resolution (never into the stock to leave);
  // X and Y to the nearest, as printed, so arcs are fitted to what is cut.
  const double q = std::pow(10.0, p.decimals);
  auto place = [&](const geometry::Vec3& v) {
    geometry::Vec3 o = v + offset;
    return geometry::Vec3{std::round(o.x * q) / q, std::round(o.y * q) / q, std::ceil(o.z * q - 1e-6) / q};
  };
  const double clearance = std::ceil((path.clearance_z + offset.z) * q - 1e-6) / q;
  if (!(p.safe_z >= clearance))
    throw std::invalid_argument("safe Z " + format_gcode_number(p.safe_z) + " is below the roughing clearance Z" +
                                format_gcode_number(clearance) + " (work coordinates)");

  geometry::Vec3 at{0, 0, p.safe_z};
  bool have_xy = false;
  auto rapid_to = [&](const geometry::Vec3& to) {
    if (have_xy) st.rapid_length += norm(to - at);
    w.rapid(to.x, to.y, to.z);
    at = to;
    have_xy = true;
  };
  auto feed_to = [&](const geometry::Vec3& to, double f) {
    if (w.feed(to.x, to.y, to.z, f)) {
      const double len = norm(to - at);
      st.cut_length += len;
      st.feed_time_s += len / f * 60.0;
    }
    at = to;
    st.work_bounds.add(to);
  };
  std::optional<ArcFitOptions> arcs = p.arcs;
  if (arcs) arcs->material_below = false;  // loops in XY: two-sided

  for (const auto& lv : path.levels)
    for (const auto& ps : lv.passes) {
      if (ps.points.empty()) continue;
      const geometry::Vec3 first = place(ps.points.front());
      if (ps.lift_before || !have_xy) {
        const double lift = std::min(p.safe_z, std::ceil((ps.lift_z + offset.z) * q - 1e-6) / q);
        if (have_xy && lift > at.z) rapid_to({at.x, at.y, lift});
        const double over = have_xy ? std::max(at.z, lift) : p.safe_z;
        rapid_to({first.x, first.y, over});
        rapid_to(first);
      } else {
        feed_to(first, p.feed);
      }
      st.work_bounds.add(first);
      const std::size_t ramp_end = std::min(ps.entry_points, ps.points.size() - 1);
      for (std::size_t k = 1; k <= ramp_end; ++k) feed_to(place(ps.points[k]), p.plunge_feed);
      std::vector<geometry::Vec3> rest;
      rest.reserve(ps.points.size() - ramp_end);
      for (std::size_t k = ramp_end; k < ps.points.size(); ++k) rest.push_back(place(ps.points[k]));
      if (rest.size() < 2) continue;
      if (!arcs) {
        for (std::size_t k = 1; k < rest.size(); ++k) feed_to(rest[k], p.feed);
        continue;
      }
      write_fitted_moves(w, fit_arcs(rest, *arcs), p.feed, st, at, &st.work_bounds);
    }
  rapid_to({at.x, at.y, p.safe_z});
}

std::string roughing_program(const cam::RoughingPath& path, const geometry::Vec3& offset, const MachiningParams& p,
                             ProgramStats* stats) {
  GcodeWriter w(p.decimals);
  write_program_start(w, p);
  w.rapid(std::nullopt, std::nullopt, p.safe_z);
  ProgramStats st;
  write_roughing(w, path, offset, p, st);
  write_program_end(w, p, st);
  if (stats) *stats = st;
  return w.text();
}

}  // namespace cncstream
