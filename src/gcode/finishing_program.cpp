#include "cncstream/gcode/finishing_program.hpp"

#include <cmath>
#include <stdexcept>

#include "cncstream/gcode/gcode_writer.hpp"

namespace cncstream {

geometry::Vec3 work_offset(const geometry::Box3& part, XYOrigin xy, ZZero z) {
  geometry::Vec3 o;
  switch (xy) {
    case XYOrigin::PartMin: o.x = -part.lo.x; o.y = -part.lo.y; break;
    case XYOrigin::PartCenter: o.x = -(part.lo.x + part.hi.x) / 2; o.y = -(part.lo.y + part.hi.y) / 2; break;
    case XYOrigin::Model: break;
  }
  switch (z) {
    case ZZero::PartTop: o.z = -part.hi.z; break;
    case ZZero::PartBottom: o.z = -part.lo.z; break;
    case ZZero::Model: break;
  }
  return o;
}

std::vector<cam::Polyline> raster_as_one_cut(const cam::RasterPath& path) {
  cam::Polyline all;
  for (std::size_t r = 0; r < path.rows.size(); ++r) {
    all.insert(all.end(), path.rows[r].begin(), path.rows[r].end());
    if (r < path.links.size()) all.insert(all.end(), path.links[r].begin(), path.links[r].end());
  }
  return {all};
}

std::string finishing_program(const cam::RasterPath& path, const geometry::Vec3& offset, const MachiningParams& p,
                              ProgramStats* stats) {
  return pieces_program(raster_as_one_cut(path), offset, p, stats);
}

namespace {

void check_feeds(const MachiningParams& p) {
  // Feeds are written with one decimal: anything below 0.1 mm/min would print as F0, which GRBL rejects.
  if (!(p.feed >= 0.1) || !(p.plunge_feed >= 0.1) || !std::isfinite(p.feed) || !std::isfinite(p.plunge_feed))
    throw std::invalid_argument("feed " + format_gcode_number(p.feed, 6) + " and plunge feed " +
                                format_gcode_number(p.plunge_feed, 6) + " mm/min must each be at least 0.1");
}

}  // namespace

void write_program_start(GcodeWriter& w, const MachiningParams& p) {
  if (!(p.rpm >= 0)) throw std::invalid_argument("spindle speed must not be negative");
  for (const auto& c : p.header_comments) w.comment(c);
  w.line("G21 G90 G17 G94");  // mm, absolute, XY plane, units/min feed
  if (p.tool > 0) w.line(std::string("T").append(std::to_string(p.tool)));
  if (p.rpm > 0) {
    w.line("M3 S" + format_gcode_number(p.rpm, 0));
    if (p.dwell_s > 0) w.line("G4 P" + format_gcode_number(p.dwell_s, 2));
  }
}

void write_program_end(GcodeWriter& w, const MachiningParams& p, ProgramStats& st) {
  if (p.rpm > 0) w.line("M5");
  w.line("M2");
  st.lines = w.lines().size();
  st.motion_lines = w.motion_lines();
}

void write_fitted_moves(GcodeWriter& w, const std::vector<FittedMove>& moves, double feed, ProgramStats& st,
                        geometry::Vec3& at, geometry::Box3* bounds) {
  for (const FittedMove& m : moves) {
    if (!m.arc) {
      if (w.feed(m.to.x, m.to.y, m.to.z, feed)) {
        const double len = norm(m.to - at);
        st.cut_length += len;
        st.feed_time_s += len / feed * 60.0;
      }
    } else {
      const int plane = m.plane == gcode::Plane::XY ? 17 : m.plane == gcode::Plane::ZX ? 18 : 19;
      if (w.arc(plane, m.clockwise, m.to.x, m.to.y, m.to.z, m.center_offset.x, m.center_offset.y, m.center_offset.z,
                feed)) {
        const double len = m.radius * m.sweep;
        st.cut_length += len;
        st.feed_time_s += len / feed * 60.0;
        ++st.arcs;
      }
    }
    at = m.to;
    if (bounds) bounds->add(m.to);
  }
}

std::string pieces_program(const std::vector<cam::Polyline>& pieces, const geometry::Vec3& offset, const MachiningParams& p,
                           ProgramStats* stats) {
  check_feeds(p);
  GcodeWriter w(p.decimals);
  write_program_start(w, p);
  ProgramStats st;
  write_pieces(w, pieces, offset, p, st);
  write_program_end(w, p, st);
  if (stats) *stats = st;
  return w.text();
}

void write_pieces(GcodeWriter& w, const std::vector<cam::Polyline>& pieces, const geometry::Vec3& offset, const MachiningParams& p,
                  ProgramStats& st) {
  check_feeds(p);
  // Z is rounded up to the output resolution so rounding never gouges.
  const double q = std::pow(10.0, p.decimals);
  auto place = [&](const geometry::Vec3& v) {
    geometry::Vec3 w = v + offset;
    w.z = std::ceil(w.z * q - 1e-6) / q;
    return w;
  };

  geometry::Box3 bounds;
  for (const auto& pl : pieces)
    for (const auto& v : pl) bounds.add(place(v));
  if (bounds.empty()) throw std::invalid_argument("tool path is empty");
  if (!(p.safe_z > bounds.hi.z + 0.5))
    throw std::invalid_argument("safe Z " + format_gcode_number(p.safe_z) + " is not at least 0.5 mm above the highest cut point Z" +
                                format_gcode_number(bounds.hi.z) + " (work coordinates)");
  st.work_bounds.add(bounds.lo);
  st.work_bounds.add(bounds.hi);

  geometry::Vec3 at;
  bool have_at = false;
  auto rapid_to = [&](std::optional<double> x, std::optional<double> y, std::optional<double> z) {
    const geometry::Vec3 to{x.value_or(at.x), y.value_or(at.y), z.value_or(at.z)};
    if (have_at) st.rapid_length += norm(to - at);
    w.rapid(x, y, z);
    at = to;
  };
  auto feed_to = [&](const geometry::Vec3& to, double f) {
    if (w.feed(to.x, to.y, to.z, f)) {
      const double len = norm(to - at);
      st.cut_length += len;
      st.feed_time_s += len / f * 60.0;
    }
    at = to;
  };
  w.rapid(std::nullopt, std::nullopt, p.safe_z);
  at.z = p.safe_z;
  // Each piece: over its start at the safe Z, plunge, cut, retract.
  for (const auto& pl : pieces) {
    if (pl.empty()) continue;
    const geometry::Vec3 first = place(pl.front());
    rapid_to(first.x, first.y, std::nullopt);
    have_at = true;
    feed_to(first, p.plunge_feed);
    if (!p.arcs) {
      for (const auto& v : pl) feed_to(place(v), p.feed);
    } else {
      // The fit sees the points as they are printed.
      std::vector<geometry::Vec3> pts;
      pts.reserve(pl.size());
      for (const auto& v : pl) {
        geometry::Vec3 w = place(v);
        w.x = std::round(w.x * q) / q;
        w.y = std::round(w.y * q) / q;
        pts.push_back(w);
      }
      write_fitted_moves(w, fit_arcs(pts, *p.arcs), p.feed, st, at);
    }
    rapid_to(std::nullopt, std::nullopt, p.safe_z);
  }
}

}  // namespace cncstream
