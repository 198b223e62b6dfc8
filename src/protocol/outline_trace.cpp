#include "cncstream/protocol/outline_trace.hpp"

#include <fmt/core.h>

#include <cmath>
#include <stdexcept>

namespace cncstream::protocol {

OutlineConfig outline_from_extent(const gcode::ProgramExtent& extent, std::optional<double> safe_z, double feed,
                                  const std::string& what, OutlineShape shape) {
  const auto& x = extent.axes[0];
  const auto& y = extent.axes[1];
  const auto& z = extent.axes[2];
  if (!x.known && !y.known) throw std::invalid_argument(what + ": the program moves neither X nor Y: no outline");
  if (!(feed > 0) || !std::isfinite(feed))
    throw std::invalid_argument(fmt::format("outline: the feed must be positive (got {})", feed));
  OutlineConfig c;
  c.x0 = x.known ? x.lo : 0;
  c.x1 = x.known ? x.hi : 0;
  c.y0 = y.known ? y.lo : 0;
  c.y1 = y.known ? y.hi : 0;
  c.feed = feed;
  if (shape == OutlineShape::Hull && x.known && y.known) {
    auto hull = gcode::simplify_hull(extent.xy_hull, kOutlineHullTolerance);
    if (hull.size() >= 3) {
      c.shape = OutlineShape::Hull;
      c.path = std::move(hull);
    }
  }
  if (!z.known && !safe_z)
    throw std::invalid_argument(what + ": the program never sets Z: give the outline's safe Z");
  const double top = z.known ? z.hi : -1e300;
  if (safe_z && z.known && *safe_z < top)
    throw std::invalid_argument(fmt::format(
        "outline: safe Z {} is below {}'s own highest Z {}: the trace would run lower than the program travels",
        routine_mm(*safe_z), what, routine_mm(top)));
  c.safe_z = safe_z ? *safe_z : top;
  return c;
}

std::vector<gcode::XyPoint> outline_corners(const OutlineConfig& c) {
  if (!c.path.empty()) return c.path;
  return {{c.x0, c.y0}, {c.x1, c.y0}, {c.x1, c.y1}, {c.x0, c.y1}};
}

OutlineTraceRoutine::OutlineTraceRoutine(OutlineConfig config) : cfg_(config) {
  if (!(cfg_.feed > 0)) throw std::invalid_argument("outline: the feed must be positive");
}

void OutlineTraceRoutine::build() {
  add([this] { wait_idle(); });
  add([this] { send("$G", false, true); });
  add([this] { send("M5"); });
  add([this] { send("G21 G90"); });
  add([this] { send("G0 Z" + routine_mm(cfg_.safe_z)); });
  add([this] { wait_idle(); });
  const std::vector<gcode::XyPoint> corners = outline_corners(cfg_);
  add([this, first = corners.front()] {
    send(fmt::format("G0 X{} Y{}", routine_mm(first[0]), routine_mm(first[1])));
  });
  add([this] { wait_idle(); });
  for (std::size_t k = 1; k <= corners.size(); ++k) {
    const gcode::XyPoint c = corners[k % corners.size()];  // back to the first at the end
    add([this, c] {
      send(fmt::format("G1 X{} Y{} F{}", routine_mm(c[0]), routine_mm(c[1]), routine_mm(cfg_.feed)));
    });
    add([this] { wait_idle(); });
  }
  add([this] {
    if (inches_) send("G20");
  });
  add([this] {
    set_summary(fmt::format("traced the {} within X{}..{} Y{}..{} at Z{} (work), F{}",
                            cfg_.shape == OutlineShape::Hull ? fmt::format("hull ({} corners)", cfg_.path.size())
                                                             : std::string("box"),
                            routine_mm(cfg_.x0), routine_mm(cfg_.x1), routine_mm(cfg_.y0), routine_mm(cfg_.y1),
                            routine_mm(cfg_.safe_z), routine_mm(cfg_.feed)));
  });
}

}  // namespace cncstream::protocol
