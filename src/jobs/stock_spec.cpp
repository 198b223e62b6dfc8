#include "cncstream/jobs/stock_spec.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace cncstream::jobs {

namespace {

double number_in(std::string_view text, std::string_view field, std::string_view what) {
  double v = 0;
  const auto* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, v);
  if (field.empty() || ec != std::errc{} || ptr != end || !std::isfinite(v))
    throw std::invalid_argument(fmt::format("--stock {}: {} '{}' is not a number", text, what, field));
  return v;
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t from = 0;
  for (;;) {
    const std::size_t at = s.find(sep, from);
    out.push_back(s.substr(from, at == std::string_view::npos ? std::string_view::npos : at - from));
    if (at == std::string_view::npos) return out;
    from = at + 1;
  }
}

geometry::Vec3 corner(std::string_view text, std::string_view field, const char* which) {
  const auto v = split(field, ',');
  if (v.size() != 3)
    throw std::invalid_argument(fmt::format("--stock {}: the {} corner '{}' needs three numbers X,Y,Z", text, which, field));
  return {number_in(text, v[0], "X"), number_in(text, v[1], "Y"), number_in(text, v[2], "Z")};
}

}  // namespace

StockSpec parse_stock_spec(std::string_view text) {
  StockSpec s;
  if (text == "auto") return s;
  if (text.rfind("auto:", 0) == 0) {
    s.margin = number_in(text, text.substr(5), "the margin");
    if (s.margin < 0) throw std::invalid_argument(fmt::format("--stock {}: the margin must not be negative", text));
    return s;
  }
  const auto corners = split(text, ':');
  if (corners.size() == 2 && text.find(',') != std::string_view::npos) {
    s.kind = StockSpec::Kind::Box;
    const geometry::Vec3 a = corner(text, corners[0], "first"), b = corner(text, corners[1], "second");
    s.box.add(a);
    s.box.add(b);
    const geometry::Vec3 size = s.box.hi - s.box.lo;
    if (!(size.x > 0 && size.y > 0 && size.z > 0))
      throw std::invalid_argument(fmt::format("--stock {}: the block has no volume (its corners share an X, Y or Z)", text));
    return s;
  }
  s.kind = StockSpec::Kind::HeightMap;
  s.height_map = std::filesystem::path(text);
  if (!std::filesystem::exists(s.height_map))
    throw std::invalid_argument(fmt::format(
        "--stock {}: not 'auto', 'auto:MARGIN', a block 'X0,Y0,Z0:X1,Y1,Z1' nor an existing height map file", text));
  return s;
}

double WorkStock::top_at(double x, double y) const {
  if (!heights) return box.hi.z;
  const cam::GridSpec& g = heights->grid;
  const double fi = std::round((x - g.x0) / g.dx), fj = std::round((y - g.y0) / g.dy);
  if (!(fi >= 0 && fj >= 0 && fi < static_cast<double>(g.nx) && fj < static_cast<double>(g.ny))) return box.hi.z;
  const float z = heights->z[static_cast<std::size_t>(fj) * g.nx + static_cast<std::size_t>(fi)];
  return std::isfinite(z) ? static_cast<double>(z) : box.hi.z;
}

WorkStock resolve_stock(const StockSpec& spec, const geometry::Box3& part) {
  WorkStock w;
  switch (spec.kind) {
    case StockSpec::Kind::Auto: {
      const geometry::Vec3 m{spec.margin, spec.margin, spec.margin};
      w.box.add(part.lo - geometry::Vec3{m.x, m.y, 0});
      w.box.add(part.hi + m);
      return w;
    }
    case StockSpec::Kind::Box: w.box = spec.box; break;
    case StockSpec::Kind::HeightMap: {
      cam::HeightFieldData d = cam::read_height_field(spec.height_map);
      if (d.work_origin) {
        const geometry::Vec3 o = *d.work_origin;
        if (!spec.work_origin)
          throw std::invalid_argument(fmt::format(
              "stock height map {} was saved with its work zero at machine X{:.3f} Y{:.3f} Z{:.3f}; this job's work "
              "zero is not known here, so the surface cannot be placed: give this job's work origin (--work-origin "
              "X,Y,Z, machine coordinates of its work zero: G54 + G92 from $#)",
              spec.height_map.string(), o.x, o.y, o.z));
        // Machine = saved work + its origin = this job's work + this origin.
        const geometry::Vec3 shift = o - *spec.work_origin;
        d.grid.x0 += shift.x;
        d.grid.y0 += shift.y;
        for (float& z : d.z)
          if (std::isfinite(z)) z = static_cast<float>(static_cast<double>(z) + shift.z);
        d.work_origin = spec.work_origin;
      }
      double top = -HUGE_VAL;
      for (const float z : d.z)
        if (std::isfinite(z)) top = std::max(top, static_cast<double>(z));
      if (!std::isfinite(top))
        throw std::invalid_argument(fmt::format("stock height map {} holds no value", spec.height_map.string()));
      w.box.add(geometry::Vec3{d.grid.x0, d.grid.y0, part.lo.z});
      w.box.add(geometry::Vec3{d.grid.x1(), d.grid.y1(), top});
      w.heights = std::move(d);
      break;
    }
  }
  const double eps = 1e-9;
  if (w.box.lo.x > part.lo.x + eps || w.box.lo.y > part.lo.y + eps || w.box.hi.x < part.hi.x - eps ||
      w.box.hi.y < part.hi.y - eps)
    throw std::invalid_argument(fmt::format(
        "the stock (X {:.3f}..{:.3f}, Y {:.3f}..{:.3f}) does not cover the part (X {:.3f}..{:.3f}, Y {:.3f}..{:.3f}) "
        "in work coordinates",
        w.box.lo.x, w.box.hi.x, w.box.lo.y, w.box.hi.y, part.lo.x, part.hi.x, part.lo.y, part.hi.y));
  if (w.box.hi.z < part.hi.z - 0.01)
    throw std::invalid_argument(fmt::format("the stock's top Z {:.3f} is below the part's top Z {:.3f} (work coordinates)",
                                            w.box.hi.z, part.hi.z));
  return w;
}

}  // namespace cncstream::jobs
