#include "cncstream/protocol/firmware_profile.hpp"

#include "cncstream/protocol/pattern.hpp"
#include "cncstream/protocol/toml_guard.hpp"

#include <algorithm>
#include <set>
#include <fstream>
#include <sstream>

#define TOML_HEADER_ONLY 1
#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

namespace cncstream::protocol {

namespace {

struct RealtimeName {
  Realtime r;
  const char* key;
};
constexpr RealtimeName kRealtimeNames[] = {
    {Realtime::StatusReport, "status_report"},   {Realtime::CycleStart, "cycle_start"},
    {Realtime::FeedHold, "feed_hold"},           {Realtime::SoftReset, "soft_reset"},
    {Realtime::SafetyDoor, "safety_door"},       {Realtime::JogCancel, "jog_cancel"},
    {Realtime::FeedOvReset, "feed_ov_reset"},    {Realtime::FeedOvPlus10, "feed_ov_plus_10"},
    {Realtime::FeedOvMinus10, "feed_ov_minus_10"}, {Realtime::FeedOvPlus1, "feed_ov_plus_1"},
    {Realtime::FeedOvMinus1, "feed_ov_minus_1"}, {Realtime::RapidOvReset, "rapid_ov_reset"},
    {Realtime::RapidOvMedium, "rapid_ov_medium"}, {Realtime::RapidOvLow, "rapid_ov_low"},
    {Realtime::SpindleOvReset, "spindle_ov_reset"}, {Realtime::SpindleOvPlus10, "spindle_ov_plus_10"},
    {Realtime::SpindleOvMinus10, "spindle_ov_minus_10"}, {Realtime::SpindleOvPlus1, "spindle_ov_plus_1"},
    {Realtime::SpindleOvMinus1, "spindle_ov_minus_1"}, {Realtime::SpindleStop, "spindle_stop"},
    {Realtime::FloodToggle, "flood_toggle"},     {Realtime::MistToggle, "mist_toggle"},
    {Realtime::Stop, "stop"},                    {Realtime::ParserStateReport, "parser_state_report"},
    {Realtime::FullStatusReport, "full_status_report"}, {Realtime::MpgToggle, "mpg_toggle"},
    {Realtime::ToolChangeAck, "tool_change_ack"},
};

std::string where(const std::filesystem::path& path, const toml::node& n) {
  const auto& s = n.source();
  return path.string() + ":" + std::to_string(s.begin.line);
}

[[noreturn]] void fail(const std::filesystem::path& path, const toml::node& n, const std::string& what) {
  throw ProfileError(where(path, n) + ": " + what);
}

std::string get_string(const std::filesystem::path& path, const toml::node& n, const char* key) {
  if (auto v = n.value<std::string>()) return *v;
  fail(path, n, std::string("'") + key + "' must be a string");
}

std::int64_t get_int(const std::filesystem::path& path, const toml::node& n, const char* key) {
  if (auto v = n.value<std::int64_t>()) return *v;
  fail(path, n, std::string("'") + key + "' must be an integer");
}

double get_number(const std::filesystem::path& path, const toml::node& n, const char* key) {
  if (auto v = n.value<double>()) return *v;
  fail(path, n, std::string("'") + key + "' must be a number");
}

std::vector<std::string> get_strings(const std::filesystem::path& path, const toml::node& n, const char* key) {
  const auto* arr = n.as_array();
  if (!arr) fail(path, n, std::string("'") + key + "' must be an array of strings");
  std::vector<std::string> out;
  for (const auto& e : *arr) out.push_back(get_string(path, e, key));
  return out;
}

void check_regexes(const std::filesystem::path& path, const toml::node& n, const std::vector<std::string>& res) {
  for (const auto& r : res) {
    if (auto err = pattern_error(r)) fail(path, n, "bad regular expression '" + r + "': " + *err);
  }
}

void read_messages(const std::filesystem::path& path, const toml::node& n,
                   std::vector<FirmwareProfile::MessageInfo>& out) {
  const auto* arr = n.as_array();
  if (!arr) fail(path, n, "'messages' must be an array of tables ([[messages]])");
  for (const auto& e : *arr) {
    const auto* t = e.as_table();
    if (!t) fail(path, e, "each 'messages' entry must be a table");
    FirmwareProfile::MessageInfo m;
    for (const auto& [k, v] : *t) {
      const std::string name(k.str());
      if (name == "pattern") m.pattern = get_string(path, v, "pattern");
      else if (name == "name") m.info.name = get_string(path, v, "name");
      else if (name == "text") m.info.text = get_string(path, v, "text");
      else if (name == "action") m.info.action = get_string(path, v, "action");
      else if (name == "position_lost") {
        auto b = v.value<bool>();
        if (!b) fail(path, v, "'position_lost' must be true or false");
        m.info.position_lost = *b;
      } else {
        fail(path, v, "unknown key '" + name + "' in messages entry");
      }
    }
    if (m.pattern.empty() || m.info.text.empty() || m.info.action.empty())
      fail(path, e, "messages entry needs 'pattern', 'text' and 'action'");
    check_regexes(path, e, {m.pattern});
    out.push_back(std::move(m));
  }
}

void read_codes(const std::filesystem::path& path, const toml::node& n, const char* key,
                std::map<int, CodeInfo>& out) {
  const auto* arr = n.as_array();
  if (!arr) fail(path, n, std::string("'") + key + "' must be an array of tables ([[" + key + "]])");
  for (const auto& e : *arr) {
    const auto* t = e.as_table();
    if (!t) fail(path, e, std::string("each '") + key + "' entry must be a table");
    CodeInfo c;
    bool have_code = false;
    for (const auto& [k, v] : *t) {
      const std::string name(k.str());
      if (name == "code") {
        c.code = static_cast<int>(get_int(path, v, "code"));
        have_code = true;
      } else if (name == "name") {
        c.name = get_string(path, v, "name");
      } else if (name == "text") {
        c.text = get_string(path, v, "text");
      } else if (name == "action") {
        c.action = get_string(path, v, "action");
      } else if (name == "reset_required") {
        auto b = v.value<bool>();
        if (!b) fail(path, v, "'reset_required' must be true or false");
        c.reset_required = *b;
      } else if (name == "position_lost") {
        auto b = v.value<bool>();
        if (!b) fail(path, v, "'position_lost' must be true or false");
        c.position_lost = *b;
      } else {
        fail(path, v, "unknown key '" + name + "' in " + key + " entry");
      }
    }
    if (!have_code) fail(path, e, std::string(key) + " entry without 'code'");
    if (c.text.empty()) fail(path, e, std::string(key) + " entry " + std::to_string(c.code) + " without 'text'");
    out[c.code] = std::move(c);
  }
}

FirmwareProfile load_impl(const std::filesystem::path& path, std::set<std::string>& chain) {
  const std::string id = path.stem().string();
  if (!chain.insert(id).second) throw ProfileError(path.string() + ": 'inherits' forms a cycle");
  toml::table tbl;
  try {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ProfileError(path.string() + ": cannot read the profile");
    std::ostringstream text;
    text << in.rdbuf();
    try {
      check_toml_text(text.str(), path.string());
    } catch (const std::invalid_argument& e) {
      throw ProfileError(e.what());
    }
    tbl = toml::parse(text.str(), path.string());
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path.string() << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
       << e.description();
    throw ProfileError(os.str());
  }

  FirmwareProfile p;
  if (const auto* base = tbl.get("inherits")) {
    const std::string base_id = get_string(path, *base, "inherits");
    const auto base_path = path.parent_path() / (base_id + ".toml");
    if (!std::filesystem::exists(base_path))
      fail(path, *base, "'inherits' names '" + base_id + "' but " + base_path.string() + " does not exist");
    p = load_impl(base_path, chain);
    p.banner_patterns.clear();
    p.version_patterns.clear();
  }
  p.id = id;

  for (const auto& [k, v] : tbl) {
    const std::string key(k.str());
    if (key == "inherits") continue;
    if (key == "family") p.family = get_string(path, v, "family");
    else if (key == "description") p.description = get_string(path, v, "description");
    else if (key == "priority") p.priority = static_cast<int>(get_int(path, v, "priority"));
    else if (key == "flow_control") {
      const auto s = get_string(path, v, "flow_control");
      if (s == "character_counting") p.flow = FlowControl::CharacterCounting;
      else if (s == "send_response") p.flow = FlowControl::SendResponse;
      else fail(path, v, "flow_control must be \"character_counting\" or \"send_response\", not \"" + s + "\"");
    } else if (key == "rx_buffer_size") {
      const auto n = get_int(path, v, key.c_str());
      if (n < 16 || n > 65536) fail(path, v, "rx_buffer_size must be within 16..65536");
      p.rx_buffer_size = static_cast<std::size_t>(n);
    } else if (key == "rx_margin") {
      const auto n = get_int(path, v, key.c_str());
      if (n < 0 || n > 64) fail(path, v, "rx_margin must be within 0..64");
      p.rx_margin = static_cast<std::size_t>(n);
    } else if (key == "line_length_limit") {
      const auto n = get_int(path, v, key.c_str());
      if (n < 8 || n > 4096) fail(path, v, "line_length_limit must be within 8..4096");
      p.line_length_limit = static_cast<std::size_t>(n);
    } else if (key == "planner_blocks") p.planner_blocks = static_cast<int>(get_int(path, v, key.c_str()));
    else if (key == "status_poll_interval_ms") {
      const double ms = get_number(path, v, key.c_str());
      if (ms < 20 || ms > 5000) fail(path, v, "status_poll_interval_ms must be within 20..5000");
      p.status_poll_interval_s = ms / 1000.0;
    } else if (key == "baud") p.baud = static_cast<unsigned>(get_int(path, v, "baud"));
    else if (key == "native_usb") {
      if (!v.is_boolean()) fail(path, v, "native_usb must be true or false");
      p.native_usb = v.value_or(false);
    } else if (key == "blocks_per_second") {
      const double r = get_number(path, v, key.c_str());
      if (!(r >= 0)) fail(path, v, "blocks_per_second must be a number >= 0");
      p.blocks_per_second = r;
    }
    else if (key == "banner_patterns") {
      p.banner_patterns = get_strings(path, v, key.c_str());
      check_regexes(path, v, p.banner_patterns);
    } else if (key == "version_patterns") {
      p.version_patterns = get_strings(path, v, key.c_str());
      check_regexes(path, v, p.version_patterns);
    } else if (key == "identify_query") p.identify_query = get_string(path, v, key.c_str());
    else if (key == "startup_lines") p.startup_lines = get_strings(path, v, key.c_str());
    else if (key == "extended_realtime") {
      auto b = v.value<bool>();
      if (!b) fail(path, v, "'extended_realtime' must be true or false");
      p.extended_realtime = *b;
    } else if (key == "send_window") {
      const auto n = get_int(path, v, key.c_str());
      if (n < 1 || n > 16) fail(path, v, "send_window must be within 1..16");
      p.send_window = static_cast<int>(n);
    } else if (key == "busy_timeout_s") p.busy_timeout_s = get_number(path, v, key.c_str());
    else if (key == "realtime") {
      const auto* t = v.as_table();
      if (!t) fail(path, v, "'realtime' must be a table");
      for (const auto& [rk, rv] : *t) {
        const std::string rname(rk.str());
        const auto r = realtime_from_key(rname);
        if (!r) fail(path, rv, "unknown real-time command '" + rname + "'");
        if (rv.is_boolean() && !*rv.value<bool>()) {  // `name = false` removes an inherited byte
          p.realtime.erase(*r);
          continue;
        }
        const auto b = get_int(path, rv, rname.c_str());
        if (b < 0 || b > 255) fail(path, rv, "real-time byte for '" + rname + "' must be within 0..255");
        p.realtime[*r] = static_cast<std::uint8_t>(b);
      }
    } else if (key == "errors") read_codes(path, v, "errors", p.errors);
    else if (key == "alarms") read_codes(path, v, "alarms", p.alarms);
    else if (key == "messages") read_messages(path, v, p.messages);
    else fail(path, v, "unknown key '" + key + "'");
  }
  if (p.family.empty()) throw ProfileError(path.string() + ": missing 'family'");
  if (p.banner_patterns.empty()) throw ProfileError(path.string() + ": missing 'banner_patterns'");
  if (p.flow == FlowControl::CharacterCounting && p.rx_margin >= p.rx_buffer_size)
    throw ProfileError(path.string() + ": rx_margin must be smaller than rx_buffer_size");
  chain.erase(id);
  return p;
}

}  // namespace

const char* realtime_key(Realtime r) {
  for (const auto& n : kRealtimeNames)
    if (n.r == r) return n.key;
  return "?";
}

std::optional<Realtime> realtime_from_key(const std::string& key) {
  for (const auto& n : kRealtimeNames)
    if (key == n.key) return n.r;
  return std::nullopt;
}

std::optional<std::uint8_t> FirmwareProfile::realtime_byte(Realtime r) const {
  auto it = realtime.find(r);
  if (it == realtime.end()) return std::nullopt;
  if (it->second >= 0x80 && !extended_realtime) return std::nullopt;
  return it->second;
}

CodeInfo FirmwareProfile::error_info(int code) const {
  if (auto it = errors.find(code); it != errors.end()) return it->second;
  CodeInfo c;
  c.code = code;
  c.name = "Unknown error";
  c.text = "error:" + std::to_string(code) + " is not in the " + id + " table.";
  c.action = "Look the code up in the controller's documentation; check the line for unsupported G-code.";
  return c;
}

std::optional<CodeInfo> FirmwareProfile::message_info(std::string_view text) const {
  for (const auto& m : messages)
    if (matches_any_pattern({m.pattern}, text)) return m.info;
  return std::nullopt;
}

CodeInfo FirmwareProfile::alarm_info(int code) const {
  if (auto it = alarms.find(code); it != alarms.end()) return it->second;
  CodeInfo c;
  c.code = code;
  c.name = "Unknown alarm";
  c.text = "ALARM:" + std::to_string(code) + " is not in the " + id + " table.";
  c.action = "Check the machine, then unlock with $X or re-home with $H.";
  c.reset_required = true;
  c.position_lost = true;
  return c;
}

FirmwareProfile load_firmware_profile(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw ProfileError(path.string() + ": no such profile file");
  std::set<std::string> chain;
  return load_impl(path, chain);
}

std::vector<FirmwareProfile> load_firmware_profiles(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) throw ProfileError(dir.string() + ": not a folder of firmware profiles");
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<FirmwareProfile> out;
  out.reserve(files.size());
  for (const auto& f : files) out.push_back(load_firmware_profile(f));
  if (out.empty()) throw ProfileError(dir.string() + ": contains no *.toml firmware profiles");
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.priority > b.priority; });
  return out;
}

FirmwareProfile conservative_grbl_subset(const FirmwareProfile& grbl11) {
  FirmwareProfile p = grbl11;
  p.id = "unknown (GRBL 1.1 subset)";
  p.family = "grbl";
  p.description = "Unrecognised controller: GRBL 1.1 line protocol without extended real-time bytes";
  p.flow = FlowControl::CharacterCounting;
  p.rx_buffer_size = 128;
  p.rx_margin = std::max<std::size_t>(p.rx_margin, 1);
  p.line_length_limit = 80;
  p.extended_realtime = false;
  p.startup_lines.clear();
  return p;
}

}  // namespace cncstream::protocol
