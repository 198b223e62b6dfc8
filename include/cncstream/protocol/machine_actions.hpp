#pragma once
// The lines of an operator's machine actions beside jogging: zero work axes,
// safe Z, go to work zero, spindle on/off and probing Z with a touch plate.
// Pure: settings and what is known of the machine in, lines out. GRBL sets
// work zero with G10 L20 P0 (the active coordinate system); Marlin has no G10
// L20 (its G10 is a retract), so it uses G92.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::protocol {

struct MachineActionSettings {
  double safe_z_mm = 5.0;                   // work Z that clears clamps and stock
  std::optional<double> safe_z_machine_mm;  // if set: G53 Z (machine coordinates) instead
  double spindle_rpm = 10000;
  double probe_plate_mm = 0;        // touch plate thickness (0: probe the stock itself)
  double probe_travel_mm = 30;      // how far down to search before giving up
  double probe_feed_mm_min = 100;
  double probe_retract_mm = 2;
};

enum class ActionFamily { Grbl, Marlin };

// `axes` is any of "X", "Y", "Z" (e.g. "XYZ"); throws std::invalid_argument otherwise.
std::vector<std::string> zero_axes_lines(std::string_view axes, ActionFamily f);
// Up to safe Z; never down when the tool is already higher (`work_z` known).
std::vector<std::string> safe_z_lines(const MachineActionSettings& s, std::optional<double> work_z);
// Safe Z first, then X0 Y0, then Z0.
std::vector<std::string> go_to_work_zero_lines(const MachineActionSettings& s, std::optional<double> work_z);
std::vector<std::string> spindle_lines(bool on, const MachineActionSettings& s);

// Probe Z (GRBL family): a G38.2 search down, answered by [PRB:x,y,z:1].
std::vector<std::string> probe_z_lines(const MachineActionSettings& s);
struct ProbeReport {
  double x = 0, y = 0, z = 0;  // machine coordinates where the probe triggered (reported units)
  bool touched = false;
};
// "[PRB:0.000,0.000,-12.345:1]" -> the report; nullopt for any other line.
std::optional<ProbeReport> parse_probe_report(std::string_view line);
// After a touch at machine Z `touch_mz` (mm): back to the touch point, set
// work Z there to the plate's thickness, retract.
std::vector<std::string> probe_finish_lines(const MachineActionSettings& s, double touch_mz);

}  // namespace cncstream::protocol
