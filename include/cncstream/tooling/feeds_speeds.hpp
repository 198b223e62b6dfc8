#pragma once
// Feeds and speeds from chip load: pure functions of the tool, the material,
// the cut's engagement and the machine's limits.
//   rpm   = 1000 Vc / (pi D_eff), within the spindle's $31..$30
//   feed  = rpm x flutes x chip load x thinning, within the axes' $110-$112
// D_eff is the diameter that cuts at the depth of cut (a ball's, a tapered
// ball's or a V-bit's is smaller than its nominal one); below half the
// diameter of radial engagement the chip is thinner than the feed per tooth,
// and the feed per tooth is raised so that the chip keeps its load.
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/tooling/tool.hpp"

namespace cncstream::tooling {

struct Material {
  std::string name;
  std::vector<std::string> aliases;
  double surface_speed_lo = 0, surface_speed_hi = 0;  // m/min
  struct ChipLoadRow {
    double diameter = 0, lo = 0, hi = 0;  // mm, mm per tooth
  };
  std::vector<ChipLoadRow> chip_load;  // by diameter, ascending

  double surface_speed() const { return (surface_speed_lo + surface_speed_hi) / 2; }
  // The middle of the chart's range at `diameter` (interpolated; in
  // proportion to the diameter below the smallest row; the largest row's
  // above it). `low` = true: the range's low end, below which the edge rubs.
  double chip_load_at(double diameter, bool low = false) const;
};

struct MaterialTable {
  std::vector<Material> materials;
  // By name or alias, case-insensitive; throws std::invalid_argument listing
  // the table's materials.
  const Material& find(std::string_view name) const;
};

// The table shipped with cncstream (src/tooling/materials.toml, with its
// sources), parsed once.
const MaterialTable& builtin_materials();
const std::string& builtin_materials_toml();
// Throws std::invalid_argument "<source>:<line>: <what>".
MaterialTable parse_material_table(std::string_view text, const std::string& source);

// rpm = 1000 Vc / (pi D): Vc in m/min, D in mm.
double rpm_for_surface_speed(double surface_speed, double diameter);
// The factor the feed per tooth is raised by at radial engagement ae of a
// tool of diameter D: D / (2 sqrt(D ae - ae^2)) below ae = D/2, else 1.
double chip_thinning_factor(double diameter, double radial_engagement);
// The diameter that cuts at depth of cut ap (mm): a ball's 2 sqrt(ap (D - ap)),
// a tapered ball's on its ball then its cone, a V-bit's tip + 2 ap tan(half
// angle), a bull's core plus its torus; never above the tool's diameter.
double effective_diameter(const ToolGeometry& g, double depth_of_cut);

// The machine's limits (0: not known, not applied).
struct MachineLimits {
  double max_feed_xy = 0;   // mm/min: min($110, $111)
  double max_feed_z = 0;    // mm/min: $112
  double spindle_max = 0;   // rpm: $30
  double spindle_min = 0;   // rpm: $31
};

// The limits a GRBL-family controller's `$$` gives (setting number ->
// value): the slower of $110/$111, $112, and with_spindle the spindle's
// $30/$31 (the built-in simulator's are GRBL's shipped 1000/0, a PWM scale,
// not a spindle's speeds). A setting missing, or not above 0, stays 0.
MachineLimits machine_limits_from_settings(const std::map<int, double>& settings, bool with_spindle = true);

struct CutRequest {
  ToolGeometry geometry;
  int flutes = 2;
  const Material* material = nullptr;     // required unless the tool's data gives rpm and feed
  const CuttingData* tool_data = nullptr; // the library's data for this tool in this material
  double depth_of_cut = 0;                // ap, mm (0: the tool's radius)
  double radial_engagement = 0;           // ae, mm (0: the whole effective diameter, a slot)
  std::optional<double> rpm, feed;        // given by the operator: they win
  MachineLimits limits;
};

struct Feeds {
  double rpm = 0;
  double feed = 0;         // mm/min
  double plunge_feed = 0;  // mm/min
  double effective_diameter = 0;
  double thinning = 1;             // the chip thinning factor applied
  double feed_per_tooth = 0;       // feed / (rpm x flutes), mm
  double chip_load = 0;            // the chip that results: feed per tooth / thinning, mm
  double removal_rate = 0;         // ap x ae x feed, mm^3/min
  // What set each: "surface speed 450 m/min", "given", "tool data",
  // "spindle max $30 = 24000", "max rate $110/$111 = 2000".
  std::string rpm_from, feed_from;
  std::vector<std::string> warnings;  // a chip below the rubbing threshold ...
};

// Throws std::invalid_argument when neither the material nor the tool's data
// nor the operator give what is needed, or for a depth or engagement < 0.
Feeds compute_feeds(const CutRequest& request);

// "T3 taper:1:5:3.175  18000 rpm (spindle max $30)  1450 mm/min  chip 0.041 mm  2.3 cm³/min".
std::string feeds_text(const Feeds& f);

}  // namespace cncstream::tooling
