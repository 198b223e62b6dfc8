#include "cncstream/protocol/corner_probe.hpp"

#include <fmt/core.h>

#include <cmath>
#include <stdexcept>

namespace cncstream::protocol {

namespace detail_corner_probe {

constexpr const char* kAxisLetter = "XYZ";

double axis_of(const geometry::Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }

// The machine position of a report: MPos, or WPos + WCO.
std::optional<geometry::Vec3> machine_position(const StatusReport& r) {
  if (r.mpos) return geometry::Vec3{(*r.mpos)[0], (*r.mpos)[1], (*r.mpos)[2]};
  if (r.wpos && r.wco)
    return geometry::Vec3{(*r.wpos)[0] + (*r.wco)[0], (*r.wpos)[1] + (*r.wco)[1], (*r.wpos)[2] + (*r.wco)[2]};
  return std::nullopt;
}

}  // namespace detail_corner_probe

const char* to_string(CornerAxes a) {
  switch (a) {
    case CornerAxes::XYZ: return "xyz";
    case CornerAxes::XY: return "xy";
    case CornerAxes::Z: return "z";
  }
  return "xyz";
}

CornerAxes parse_corner_axes(const std::string& text) {
  if (text == "xyz" || text == "corner") return CornerAxes::XYZ;
  if (text == "xy") return CornerAxes::XY;
  if (text == "z") return CornerAxes::Z;
  throw std::invalid_argument("corner probe '" + text + "': expected corner (xyz), xy or z");
}

void validate(const CornerProbeConfig& c) {
  const auto positive = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(fmt::format("corner probe: {} must be a positive number of mm (got {})", what, v));
  };
  positive(c.plate.thickness, "the plate's thickness");
  positive(c.plate.size, "the plate's size");
  positive(c.z_travel, "the Z travel");
  positive(c.fast_feed, "the fast probe feed");
  positive(c.slow_feed, "the slow probe feed");
  positive(c.retract, "the retract");
  positive(c.clearance, "the clearance");
  positive(c.side_depth, "the side depth");
  if (!(c.plate.lip >= 0) || !(c.plate.lip < c.plate.size))
    throw std::invalid_argument(
        fmt::format("corner probe: the plate's lip ({} mm) must be at least 0 and less than its size", c.plate.lip));
  if (!(c.tool_radius >= 0) || !std::isfinite(c.tool_radius))
    throw std::invalid_argument(fmt::format("corner probe: the tool's radius ({} mm) must be at least 0", c.tool_radius));
}

CornerProbeRoutine::CornerProbeRoutine(CornerProbeConfig config) : cfg_(config) { validate(cfg_); }

void CornerProbeRoutine::add_input_clear(const char* when) {
  add([this, when] {
    if (pin_active_)
      fail(fmt::format("the probe input is active {} (plate touching the bit, clip shorted): refused", when));
  });
}

void CornerProbeRoutine::add_probe(int axis, double dir, double travel, double* out) {
  using detail_corner_probe::kAxisLetter;
  const char letter = kAxisLetter[axis];
  add_input_clear("before probing");
  add([this, letter, dir, travel] {
    send(fmt::format("G91 G38.2 {}{} F{}", letter, routine_mm(dir * travel), routine_mm(cfg_.fast_feed)), true);
  });
  add([this, letter, travel] {
    if (!probe_ || !probe_->touched)
      fail(fmt::format("no contact within {} mm along {}: is the plate there and its clip on?", routine_mm(travel),
                       letter));
  });
  add([this, letter, dir] { send(fmt::format("G0 {}{}", letter, routine_mm(-dir * cfg_.retract))); });
  add([this] { wait_idle(); });
  add_input_clear("after backing off");
  add([this, letter, dir] {
    send(fmt::format("G38.2 {}{} F{}", letter, routine_mm(dir * 2 * cfg_.retract), routine_mm(cfg_.slow_feed)),
         true);
  });
  add([this, axis, out, letter] {
    if (!probe_ || !probe_->touched) {
      fail(fmt::format("the slow probe along {} did not trigger", letter));
      return;
    }
    *out = axis == 0 ? probe_->x : axis == 1 ? probe_->y : probe_->z;
  });
  add([this, letter, dir] { send(fmt::format("G0 {}{}", letter, routine_mm(-dir * cfg_.retract))); });
}

// Beside the plate at the travel height: down to the side depth with G38.3,
// which stops (and fails here) if anything conductive is under the bit.
void CornerProbeRoutine::add_lower_beside() {
  add([this] {
    send(fmt::format("G91 G38.3 Z{} F{}", routine_mm(-(cfg_.clearance + cfg_.side_depth)),
                     routine_mm(cfg_.fast_feed)),
         true);
  });
  add([this] {
    if (probe_ && probe_->touched) fail("something touched the bit while lowering it beside the plate");
  });
}

void CornerProbeRoutine::build() {
  using detail_corner_probe::machine_position;
  add([this] { wait_idle(); });
  add_input_clear("before probing");
  add([this] { send("$G", false, true); });
  add([this] {
    if (!wcs_) fail("$G did not report the active work offset (G54..G59)");
  });
  add([this] { send("$#", false, true); });
  add([this] {
    const std::string name = fmt::format("G5{}", 4 + *wcs_);
    if (!offsets_.count(name)) {
      fail("$# did not report " + name);
      return;
    }
    result_.wcs = *wcs_;
    result_.offset_before = offsets_[name];
    result_.offset_written = result_.offset_before;
    const auto at = status_ ? machine_position(*status_) : std::nullopt;
    if (!at) {
      fail("no machine position reported (MPos or WPos with WCO)");
      return;
    }
    start_ = *at;
  });
  add([this] { send("G21"); });
  // Z: the plate's top.
  add_probe(2, -1, cfg_.z_travel, &top_trigger_);
  const bool sides = cfg_.axes != CornerAxes::Z;
  // Travel at a machine height `clearance` above the plate's top.
  add([this] { send("G53 G0 Z" + routine_mm(top_trigger_ + cfg_.clearance)); });
  if (sides) {
    // Far enough out that the whole cutter clears the wall wherever on the
    // plate's top the bit started (it touched the top: its axis is within a
    // radius of it); the probe goes no further back than the start.
    const double out = cfg_.plate.size + 2 * cfg_.tool_radius + cfg_.clearance;
    add([this, out] {
      send(fmt::format("G53 G0 X{} Y{}", routine_mm(start_.x - out), routine_mm(start_.y)));
    });
    add_lower_beside();
    add_probe(0, +1, out, &x_trigger_);
    add([this] { send("G53 G0 Z" + routine_mm(top_trigger_ + cfg_.clearance)); });
    add([this, out] {
      send(fmt::format("G53 G0 X{} Y{}", routine_mm(start_.x), routine_mm(start_.y - out)));
    });
    add_lower_beside();
    add_probe(1, +1, out, &y_trigger_);
    add([this] { send("G53 G0 Z" + routine_mm(top_trigger_ + cfg_.clearance)); });
    add([this] { send(fmt::format("G53 G0 X{} Y{}", routine_mm(start_.x), routine_mm(start_.y))); });
  }
  add([this] { send(inches_ ? "G90 G20" : "G90"); });
  add([this] { wait_idle(); });
  // The result, shown before it is written.
  add([this, sides] {
    const std::string name = fmt::format("G5{}", 4 + result_.wcs);
    const geometry::Vec3 g92 = offsets_.count("G92") ? offsets_["G92"] : geometry::Vec3{};
    const double tlo = offsets_.count("TLO") ? offsets_["TLO"].z : 0.0;
    geometry::Vec3& w = result_.offset_written;
    std::string found;
    if (sides) {
      result_.edge_x = x_trigger_ + cfg_.tool_radius + cfg_.plate.lip;
      result_.edge_y = y_trigger_ + cfg_.tool_radius + cfg_.plate.lip;
      w.x = *result_.edge_x - g92.x;
      w.y = *result_.edge_y - g92.y;
      found += fmt::format("X edge at machine X{}, Y edge at machine Y{}", routine_mm(*result_.edge_x),
                           routine_mm(*result_.edge_y));
    }
    if (cfg_.axes != CornerAxes::XY) {
      result_.top_z = top_trigger_ - cfg_.plate.thickness;
      w.z = *result_.top_z - g92.z - tlo;
      found += fmt::format("{}top at machine Z{}", found.empty() ? "" : ", ", routine_mm(*result_.top_z));
    }
    const geometry::Vec3& b = result_.offset_before;
    prompt(fmt::format("corner probe: {}. Set {} to X{} Y{} Z{} (was X{} Y{} Z{}; work zero moves by {:+.3f}, "
                       "{:+.3f}, {:+.3f} mm)? Remove the plate, then confirm to write it, or decline",
                       found, name, routine_mm(w.x), routine_mm(w.y), routine_mm(w.z), routine_mm(b.x),
                       routine_mm(b.y), routine_mm(b.z), w.x - b.x, w.y - b.y, w.z - b.z));
  });
  add([this, sides] {
    const geometry::Vec3& w = result_.offset_written;
    std::string words;
    if (sides) words += fmt::format(" X{} Y{}", routine_mm(w.x), routine_mm(w.y));
    if (cfg_.axes != CornerAxes::XY) words += " Z" + routine_mm(w.z);
    send(fmt::format("G10 L2 P{}{}", result_.wcs + 1, words));
  });
  add([this] { wait_idle(); });
  add([this] { send("$#", false, true); });
  add([this, sides] {
    const std::string name = fmt::format("G5{}", 4 + result_.wcs);
    const auto it = offsets_.find(name);
    const geometry::Vec3& w = result_.offset_written;
    const bool z = cfg_.axes != CornerAxes::XY;
    const auto off = [](double a, double b) { return std::fabs(a - b) > 0.0015; };
    if (it == offsets_.end() || (sides && (off(it->second.x, w.x) || off(it->second.y, w.y))) ||
        (z && off(it->second.z, w.z))) {
      fail(fmt::format("the work offset read back ({}) is not the one written (X{} Y{} Z{})",
                       it == offsets_.end() ? std::string("none")
                                            : fmt::format("X{} Y{} Z{}", routine_mm(it->second.x),
                                                          routine_mm(it->second.y), routine_mm(it->second.z)),
                       routine_mm(w.x), routine_mm(w.y), routine_mm(w.z)));
      return;
    }
    result_.applied = true;
    set_summary(fmt::format("{} set to X{} Y{} Z{} ({} probed, read back)", name, routine_mm(w.x), routine_mm(w.y),
                            routine_mm(w.z), to_string(cfg_.axes)));
  });
}

}  // namespace cncstream::protocol
