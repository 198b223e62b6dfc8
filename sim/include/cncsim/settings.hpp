#pragma once
// GRBL 1.1 '$' settings and the firmware's EEPROM contents (settings, stored
// coordinate systems, startup lines, build info), with the firmware's
// validation rules and a plain-text file to persist them between runs.
#include <array>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/motion_planner.hpp"

namespace cncsim {

class Settings {
 public:
  static Settings defaults();  // GRBL's DEFAULTS_GENERIC

  double get(int n) const;
  bool has(int n) const { return values_.count(n) != 0; }
  // Validates and stores like settings_store_global_setting(); returns the
  // GRBL status (0, 3 unknown, 4 negative, 6 pulse < 3 us, 10 soft limits
  // without homing, 12 step rate > 30 kHz).
  int set(int n, double value);
  // "$0=10\r\n$1=25\r\n..." in the firmware's order and number formats.
  std::string report() const;

  cncstream::gcode::MotionLimits motion_limits() const;
  bool report_machine_position() const { return (static_cast<int>(get(10)) & 1) != 0; }
  bool report_buffer_state() const { return (static_cast<int>(get(10)) & 2) != 0; }
  bool report_inches() const { return get(13) != 0; }
  bool soft_limits() const { return get(20) != 0; }
  bool hard_limits() const { return get(21) != 0; }
  bool homing() const { return get(22) != 0; }
  double arc_tolerance() const { return get(12); }
  cncstream::geometry::Vec3 max_travel() const { return {get(130), get(131), get(132)}; }

  const std::map<int, double>& values() const { return values_; }

 private:
  std::map<int, double> values_;
};

struct PersistentStore {
  Settings settings = Settings::defaults();
  cncstream::gcode::CoordinateTable coords;
  std::array<std::string, 2> startup_lines;  // $N0, $N1
  std::string build_info;                    // $I=
};

class StoreFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Text file: "$n=value", "G54=x,y,z" ... "G59=", "G28=", "G30=", "N0=line",
// "N1=line", "I=info", '#' comments. A missing file gives the defaults.
PersistentStore load_store(const std::filesystem::path& path);
void save_store(const std::filesystem::path& path, const PersistentStore& store);

}  // namespace cncsim
