#include "cncstream/tooling/feeds_speeds.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "toml_read.hpp"
#include "lower_case.hpp"

namespace cncstream::tooling {

namespace detail_feeds {

using detail_lower_case::lower;

double deg(double d) { return d * std::numbers::pi / 180; }

[[noreturn]] void fail(const std::string& source, const toml::node& n, const std::string& what) {
  throw std::invalid_argument(fmt::format("{}:{}: {}", source, n.source().begin.line, what));
}

double number(const std::string& source, const toml::node& n, const char* what) {
  if (n.is_integer()) return double(n.as_integer()->get());
  if (n.is_floating_point()) return n.as_floating_point()->get();
  fail(source, n, fmt::format("{}: expected a number", what));
}

}  // namespace detail_feeds

double Material::chip_load_at(double diameter, bool low) const {
  if (chip_load.empty() || !(diameter > 0)) return 0;
  auto at = [&](const ChipLoadRow& r) { return low ? r.lo : (r.lo + r.hi) / 2; };
  const auto& first = chip_load.front();
  if (diameter <= first.diameter) return at(first) * diameter / first.diameter;
  for (std::size_t k = 1; k < chip_load.size(); ++k) {
    const auto& a = chip_load[k - 1];
    const auto& b = chip_load[k];
    if (diameter <= b.diameter) {
      const double t = (diameter - a.diameter) / (b.diameter - a.diameter);
      return at(a) + t * (at(b) - at(a));
    }
  }
  return at(chip_load.back());
}

const Material& MaterialTable::find(std::string_view name) const {
  const std::string want = detail_feeds::lower(name);
  for (const auto& m : materials) {
    if (detail_feeds::lower(m.name) == want) return m;
    for (const auto& a : m.aliases)
      if (detail_feeds::lower(a) == want) return m;
  }
  std::string known;
  for (const auto& m : materials) {
    known += known.empty() ? "" : ", ";
    known += m.name;
    if (!m.aliases.empty()) {
      known += " (";
      for (std::size_t k = 0; k < m.aliases.size(); ++k) {
        known.append(k ? ", " : "");
        known.append(m.aliases[k]);
      }
      known += ")";
    }
  }
  throw std::invalid_argument(fmt::format("unknown material '{}': known are {}", name, known));
}

MaterialTable parse_material_table(std::string_view text, const std::string& source) {
  using detail_feeds::fail;
  using detail_feeds::number;
  const toml::table root = detail_toml_read::parse_toml(text, source);
  MaterialTable table;
  const auto* arr = root["material"].as_array();
  if (!arr) throw std::invalid_argument(source + ": no [[material]] tables");
  for (const auto& e : *arr) {
    const auto* t = e.as_table();
    if (!t) fail(source, e, "material: expected a table");
    Material m;
    const auto* name = t->get("name");
    if (!name || !name->is_string()) fail(source, e, "material: name: expected a string");
    m.name = name->as_string()->get();
    if (const auto* al = t->get("aliases")) {
      const auto* a = al->as_array();
      if (!a) fail(source, *al, "aliases: expected an array of strings");
      for (const auto& s : *a) {
        if (!s.is_string()) fail(source, s, "aliases: expected strings");
        m.aliases.push_back(s.as_string()->get());
      }
    }
    const auto* vc = t->get("surface_speed");
    const auto* vca = vc ? vc->as_array() : nullptr;
    if (!vca || vca->size() != 2) fail(source, vc ? *vc : e, m.name + ": surface_speed: expected [low, high] in m/min");
    m.surface_speed_lo = number(source, *vca->get(0), "surface_speed");
    m.surface_speed_hi = number(source, *vca->get(1), "surface_speed");
    if (!(m.surface_speed_lo > 0 && m.surface_speed_lo <= m.surface_speed_hi))
      fail(source, *vc, m.name + ": surface_speed: expected 0 < low <= high");
    const auto* cl = t->get("chip_load");
    const auto* cla = cl ? cl->as_array() : nullptr;
    if (!cla || cla->empty()) fail(source, cl ? *cl : e, m.name + ": chip_load: expected [[diameter, low, high], ...]");
    for (const auto& row : *cla) {
      const auto* r = row.as_array();
      if (!r || r->size() != 3) fail(source, row, m.name + ": chip_load: expected rows [diameter, low, high]");
      Material::ChipLoadRow c{number(source, *r->get(0), "diameter"), number(source, *r->get(1), "chip load"),
                              number(source, *r->get(2), "chip load")};
      if (!(c.diameter > 0 && c.lo > 0 && c.lo <= c.hi) ||
          (!m.chip_load.empty() && !(c.diameter > m.chip_load.back().diameter)))
        fail(source, row, m.name + ": chip_load: expected ascending diameters and 0 < low <= high");
      m.chip_load.push_back(c);
    }
    table.materials.push_back(std::move(m));
  }
  return table;
}

const MaterialTable& builtin_materials() {
  static const MaterialTable table = parse_material_table(builtin_materials_toml(), "materials.toml (built in)");
  return table;
}

double rpm_for_surface_speed(double surface_speed, double diameter) {
  return 1000 * surface_speed / (std::numbers::pi * diameter);
}

double chip_thinning_factor(double diameter, double ae) {
  if (!(ae > 0) || ae >= diameter / 2) return 1;
  return diameter / (2 * std::sqrt(diameter * ae - ae * ae));
}

double effective_diameter(const ToolGeometry& g, double ap) {
  using detail_feeds::deg;
  const double d = g.cutting_diameter();
  if (!(ap > 0)) return d;
  switch (g.shape) {
    case ToolShape::Flat: return d;
    case ToolShape::Ball: return ap >= d / 2 ? d : 2 * std::sqrt(ap * (d - ap));
    case ToolShape::Bull: {
      const double r = g.corner_radius, core = d / 2 - r;
      return ap >= r ? d : 2 * (core + std::sqrt(ap * (2 * r - ap)));
    }
    case ToolShape::VBit: return std::min(d, g.tip_diameter + 2 * ap * std::tan(deg(g.angle / 2)));
    case ToolShape::TaperedBall: {
      const double r = g.tip_diameter / 2, a = deg(g.angle);
      const double tangent_height = r * (1 - std::sin(a));
      const double e = ap <= tangent_height ? 2 * std::sqrt(ap * (2 * r - ap))
                                            : 2 * (r * std::cos(a) + (ap - tangent_height) * std::tan(a));
      return g.diameter > 0 ? std::min(e, g.diameter) : e;
    }
  }
  return d;
}

Feeds compute_feeds(const CutRequest& q) {
  if (q.depth_of_cut < 0 || q.radial_engagement < 0)
    throw std::invalid_argument("feeds: the depth of cut and the radial engagement must not be negative");
  Feeds f;
  const double ap = q.depth_of_cut > 0 ? q.depth_of_cut : q.geometry.cutting_diameter() / 2;
  f.effective_diameter = effective_diameter(q.geometry, ap);
  const double d = f.effective_diameter;
  const double ae = q.radial_engagement > 0 ? std::min(q.radial_engagement, d) : d;
  f.thinning = chip_thinning_factor(d, ae);
  const CuttingData* data = q.tool_data;
  const Material* m = q.material;
  auto need = [&](const char* what) {
    if (!m)
      throw std::invalid_argument(fmt::format("feeds: no {} given and no material to compute it from (--material)", what));
  };

  // The spindle speed.
  if (q.rpm) {
    f.rpm = *q.rpm;
    f.rpm_from = "given";
  } else if (data && data->rpm) {
    f.rpm = *data->rpm;
    f.rpm_from = "the tool's data for " + data->material;
  } else {
    double vc = 0;
    if (data && data->surface_speed) {
      vc = *data->surface_speed;
    } else {
      need("rpm");
      vc = m->surface_speed();
    }
    f.rpm = rpm_for_surface_speed(vc, d);
    f.rpm_from = fmt::format("surface speed {:.0f} m/min at {:.3g} mm", vc, d);
  }
  if (!q.rpm) {
    if (q.limits.spindle_max > 0 && f.rpm > q.limits.spindle_max) {
      f.rpm_from = fmt::format("spindle max $30 = {:.0f} (wanted {:.0f}: {})", q.limits.spindle_max, f.rpm, f.rpm_from);
      f.rpm = q.limits.spindle_max;
    } else if (q.limits.spindle_min > 0 && f.rpm < q.limits.spindle_min) {
      f.rpm_from = fmt::format("spindle min $31 = {:.0f} (wanted {:.0f}: {})", q.limits.spindle_min, f.rpm, f.rpm_from);
      f.rpm = q.limits.spindle_min;
    }
  }
  if (!(f.rpm > 0)) throw std::invalid_argument("feeds: the spindle speed must be positive to compute a feed");

  // The feed.
  if (q.feed) {
    f.feed = *q.feed;
    f.feed_from = "given";
  } else if (data && data->feed) {
    f.feed = *data->feed;
    f.feed_from = "the tool's data for " + data->material;
  } else {
    double cl = 0;
    if (data && data->chip_load) {
      cl = *data->chip_load;
      f.feed_from = fmt::format("chip load {:.3g} mm (tool data)", cl);
    } else {
      need("feed");
      cl = m->chip_load_at(d);
      f.feed_from = fmt::format("chip load {:.3g} mm ({} at {:.3g} mm)", cl, m->name, d);
    }
    if (f.thinning > 1) f.feed_from += fmt::format(", x{:.2f} for chip thinning", f.thinning);
    f.feed = f.rpm * q.flutes * cl * f.thinning;
  }
  if (!q.feed && q.limits.max_feed_xy > 0 && f.feed > q.limits.max_feed_xy) {
    const double wanted = f.feed;
    f.feed_from = fmt::format("max rate $110/$111 = {:.0f} (wanted {:.0f}: {})", q.limits.max_feed_xy, f.feed, f.feed_from);
    f.feed = q.limits.max_feed_xy;
    // A computed spindle speed comes down with the feed, so that the chip keeps
    // its load (a thin chip rubs and, in wood, burns); not below $31.
    if (!q.rpm && !(data && data->rpm)) {
      const double slower = std::max(f.rpm * f.feed / wanted, q.limits.spindle_min);
      // Where the spindle's top bound it before, the plan still says so.
      const bool at_spindle_max = f.rpm_from.rfind("spindle max $30", 0) == 0;
      f.rpm_from = fmt::format("lowered from {:.0f}{} with the feed to keep the chip{}", f.rpm,
                               at_spindle_max ? fmt::format(" (spindle max $30 = {:.0f})", q.limits.spindle_max)
                                              : std::string(),
                               slower == q.limits.spindle_min ? fmt::format(", to spindle min $31 = {:.0f}", slower)
                                                              : std::string());
      f.rpm = slower;
    }
  }
  f.plunge_feed = data && data->plunge_feed ? *data->plunge_feed : f.feed / 3;
  if (q.limits.max_feed_z > 0) f.plunge_feed = std::min(f.plunge_feed, q.limits.max_feed_z);

  f.feed_per_tooth = f.feed / (f.rpm * q.flutes);
  f.chip_load = f.feed_per_tooth / f.thinning;
  f.removal_rate = ap * ae * f.feed;
  if (m) {
    const double rubbing = m->chip_load_at(d, true) / 2;
    if (f.chip_load < rubbing)
      f.warnings.push_back(fmt::format("chip load {:.3g} mm is below half the chart's low end for {} at {:.3g} mm "
                                       "({:.3g} mm): the edge rubs and heats{}",
                                       f.chip_load, m->name, d, 2 * rubbing,
                                       m->name.find("wood") != std::string::npos || m->name == "mdf" || m->name == "plywood"
                                           ? " (burns wood)"
                                           : ""));
    const double high = 2 * m->chip_load_at(d) - m->chip_load_at(d, true);
    if (f.chip_load > 1.5 * high)
      f.warnings.push_back(fmt::format("chip load {:.3g} mm is well above the chart's range for {}: risk of breaking "
                                       "the tool",
                                       f.chip_load, m->name));
  }
  return f;
}

MachineLimits machine_limits_from_settings(const std::map<int, double>& settings, bool with_spindle) {
  auto get = [&](int n) {
    const auto it = settings.find(n);
    return it != settings.end() && it->second > 0 ? it->second : 0.0;
  };
  MachineLimits l;
  const double x = get(110), y = get(111);
  l.max_feed_xy = x > 0 && y > 0 ? std::min(x, y) : std::max(x, y);
  l.max_feed_z = get(112);
  if (with_spindle) {
    l.spindle_max = get(30);
    l.spindle_min = get(31);
  }
  return l;
}

std::string feeds_text(const Feeds& f) {
  return fmt::format("{:.0f} rpm, feed {:.0f} mm/min, chip {:.3f} mm/tooth, {:.2f} cm³/min", f.rpm, f.feed, f.chip_load,
                     f.removal_rate / 1000);
}

}  // namespace cncstream::tooling
