#include "cncsim/settings.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "cncsim/number_text.hpp"

namespace cncsim {
namespace {

// Settings the firmware prints as integers.
constexpr std::array kIntegerSettings{0, 1, 2, 3, 4, 5, 6, 10, 13, 20, 21, 22, 23, 26, 30, 31, 32};
bool is_integer_setting(int n) {
  return std::find(kIntegerSettings.begin(), kIntegerSettings.end(), n) != kIntegerSettings.end();
}
constexpr double kMaxStepRateHz = 30000;

std::string format_value(int n, double v) {
  if (is_integer_setting(n)) return fmt::format("{:.0f}", v);
  return fmt::format("{:.3f}", v);
}

}  // namespace

Settings Settings::defaults() {
  Settings s;
  s.values_ = {{0, 10},    {1, 25},    {2, 0},     {3, 0},     {4, 0},     {5, 0},     {6, 0},
               {10, 1},    {11, 0.010}, {12, 0.002}, {13, 0},  {20, 0},    {21, 0},    {22, 0},
               {23, 0},    {24, 25},   {25, 500},  {26, 250},  {27, 1},    {30, 1000}, {31, 0},
               {32, 0},    {100, 250}, {101, 250}, {102, 250}, {110, 500}, {111, 500}, {112, 500},
               {120, 10},  {121, 10},  {122, 10},  {130, 200}, {131, 200}, {132, 200}};
  return s;
}

double Settings::get(int n) const {
  auto it = values_.find(n);
  return it == values_.end() ? 0.0 : it->second;
}

int Settings::set(int n, double value) {
  if (!values_.count(n)) return 3;
  if (value < 0) return 4;
  if (n == 0 && value < 3) return 6;
  if (n == 20 && value != 0 && !homing()) return 10;
  if (n >= 100 && n <= 102 && value * get(n + 10) > kMaxStepRateHz * 60) return 12;
  if (n >= 110 && n <= 112 && value * get(n - 10) > kMaxStepRateHz * 60) return 12;
  if (is_integer_setting(n)) value = std::trunc(value);
  values_[n] = value;
  if (n == 22 && value == 0) values_[20] = 0;  // soft limits need homing
  return 0;
}

std::string Settings::report() const {
  std::string out;
  for (const auto& [n, v] : values_) {
    out += fmt::format("${}=", n);
    out += format_value(n, v);
    out += "\r\n";
  }
  return out;
}

cncstream::gcode::MotionLimits Settings::motion_limits() const {
  cncstream::gcode::MotionLimits m;
  m.max_rate = {get(110), get(111), get(112)};
  m.acceleration = {get(120), get(121), get(122)};
  m.junction_deviation = get(11);
  return m;
}

PersistentStore load_store(const std::filesystem::path& path) {
  PersistentStore store;
  std::ifstream in(path);
  if (!in) return store;
  std::string line;
  std::size_t lineno = 0;
  auto fail = [&](const std::string& why) {
    throw StoreFileError(path.string() + ":" + std::to_string(lineno) + ": " + why + ": '" + line + "'");
  };
  auto parse_vec = [&](const std::string& text) {
    const auto v = vec3_from(text);
    if (!v) fail("expected x,y,z");
    return *v;
  };
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) fail("expected key=value");
    const std::string key = line.substr(0, eq), value = line.substr(eq + 1);
    if (key.size() > 1 && key[0] == '$') {
      char* end = nullptr;
      const long n = std::strtol(key.c_str() + 1, &end, 10);
      const double v = std::strtod(value.c_str(), nullptr);
      if (*end != 0 || !store.settings.has(static_cast<int>(n))) fail("unknown setting");
      // Stored values are trusted as the firmware trusts its EEPROM, but must be numbers.
      if (value.empty()) fail("missing value");
      const int status = store.settings.set(static_cast<int>(n), v);
      if (status != 0 && status != 10) fail("invalid value (error:" + std::to_string(status) + ")");
    } else if (key.size() == 3 && key[0] == 'G' && key[1] == '5' && key[2] >= '4' && key[2] <= '9') {
      store.coords.wcs[static_cast<std::size_t>(key[2] - '4')] = parse_vec(value);
    } else if (key == "G28") {
      store.coords.g28 = parse_vec(value);
    } else if (key == "G30") {
      store.coords.g30 = parse_vec(value);
    } else if (key == "N0" || key == "N1") {
      store.startup_lines[key == "N0" ? 0 : 1] = value;
    } else if (key == "I") {
      store.build_info = value;
    } else {
      fail("unknown key");
    }
  }
  return store;
}

void save_store(const std::filesystem::path& path, const PersistentStore& store) {
  std::ostringstream out;
  out << "# cncsim EEPROM image: GRBL settings, coordinate systems, startup lines\n";
  for (const auto& [n, v] : store.settings.values()) out << "$" << n << "=" << v << "\n";
  auto vec = [&](const char* key, const cncstream::geometry::Vec3& v) {
    out << fmt::format("{}={:.17g},{:.17g},{:.17g}\n", key, v.x, v.y, v.z);
  };
  const char* names[] = {"G54", "G55", "G56", "G57", "G58", "G59"};
  for (std::size_t i = 0; i < 6; ++i) vec(names[i], store.coords.wcs[i]);
  vec("G28", store.coords.g28);
  vec("G30", store.coords.g30);
  out << "N0=" << store.startup_lines[0] << "\nN1=" << store.startup_lines[1] << "\n";
  out << "I=" << store.build_info << "\n";
  const auto tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::trunc);
    if (!f) throw StoreFileError("cannot write settings file " + tmp);
    f << out.str();
    if (!f) throw StoreFileError("cannot write settings file " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace cncsim
