#include "cncstream/protocol/status_report.hpp"

#include <charconv>
#include <cstdlib>
#include <vector>

namespace cncstream::protocol {

const char* to_string(MachineState s) {
  switch (s) {
    case MachineState::Unknown: return "Unknown";
    case MachineState::Idle: return "Idle";
    case MachineState::Run: return "Run";
    case MachineState::Hold: return "Hold";
    case MachineState::Jog: return "Jog";
    case MachineState::Alarm: return "Alarm";
    case MachineState::Door: return "Door";
    case MachineState::Check: return "Check";
    case MachineState::Home: return "Home";
    case MachineState::Sleep: return "Sleep";
    case MachineState::Tool: return "Tool";
  }
  return "Unknown";
}

namespace {

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (;;) {
    const auto p = s.find(sep, start);
    out.push_back(s.substr(start, p == std::string_view::npos ? std::string_view::npos : p - start));
    if (p == std::string_view::npos) break;
    start = p + 1;
  }
  return out;
}

bool parse_double(std::string_view s, double& out) {
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc{} && r.ptr == s.data() + s.size();
}

template <class Int>
bool parse_int(std::string_view s, Int& out) {
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc{} && r.ptr == s.data() + s.size();
}

bool parse_axes(std::string_view s, Axes& out, int& count) {
  const auto parts = split(s, ',');
  if (parts.empty() || parts.size() > out.size()) return false;
  out.fill(0.0);
  for (std::size_t i = 0; i < parts.size(); ++i)
    if (!parse_double(parts[i], out[i])) return false;
  count = static_cast<int>(parts.size());
  return true;
}

bool set_fail(std::string* error, std::string msg) {
  if (error) *error = std::move(msg);
  return false;
}

bool parse_state(std::string_view s, StatusReport& r, std::string* error) {
  r.state_text = std::string(s);
  std::string_view name = s;
  std::string_view sub;
  if (const auto c = s.find(':'); c != std::string_view::npos) {
    name = s.substr(0, c);
    sub = s.substr(c + 1);
  }
  static constexpr std::pair<const char*, MachineState> kStates[] = {
      {"Idle", MachineState::Idle},   {"Run", MachineState::Run},     {"Hold", MachineState::Hold},
      {"Jog", MachineState::Jog},     {"Alarm", MachineState::Alarm}, {"Door", MachineState::Door},
      {"Check", MachineState::Check}, {"Home", MachineState::Home},   {"Sleep", MachineState::Sleep},
      {"Tool", MachineState::Tool}};
  for (const auto& [n, st] : kStates)
    if (name == n) r.state = st;
  if (r.state == MachineState::Unknown) return set_fail(error, "unknown machine state '" + std::string(s) + "'");
  if (!sub.empty() && !parse_int(sub, r.substate))
    return set_fail(error, "bad sub-state in '" + std::string(s) + "'");
  return true;
}

}  // namespace

std::optional<StatusReport> parse_status_report(std::string_view line, std::string* error) {
  if (line.size() < 3 || line.front() != '<' || line.back() != '>') {
    set_fail(error, "status report must be enclosed in <...>");
    return std::nullopt;
  }
  const auto fields = split(line.substr(1, line.size() - 2), '|');
  StatusReport r;
  if (!parse_state(fields[0], r, error)) return std::nullopt;
  for (std::size_t i = 1; i < fields.size(); ++i) {
    const auto f = fields[i];
    const auto c = f.find(':');
    const auto key = f.substr(0, c);
    const auto val = c == std::string_view::npos ? std::string_view{} : f.substr(c + 1);
    auto bad = [&] {
      set_fail(error, "bad value in status field '" + std::string(f) + "'");
      return std::nullopt;
    };
    if (key == "MPos" || key == "WPos" || key == "WCO") {
      Axes a{};
      int n = 0;
      if (!parse_axes(val, a, n)) return bad();
      r.axis_count = std::max(r.axis_count, n);
      (key == "MPos" ? r.mpos : key == "WPos" ? r.wpos : r.wco) = a;
    } else if (key == "Bf") {
      const auto p = split(val, ',');
      int a = 0, b = 0;
      if (p.size() != 2 || !parse_int(p[0], a) || !parse_int(p[1], b)) return bad();
      r.planner_free = a;
      r.rx_free = b;
    } else if (key == "FS") {
      const auto p = split(val, ',');
      double a = 0, b = 0;
      if (p.size() < 2 || !parse_double(p[0], a) || !parse_double(p[1], b)) return bad();
      r.feed = a;
      r.spindle = b;
    } else if (key == "F") {
      double a = 0;
      if (!parse_double(val, a)) return bad();
      r.feed = a;
    } else if (key == "Ov") {
      const auto p = split(val, ',');
      std::array<int, 3> ov{};
      if (p.size() != 3) return bad();
      for (int k = 0; k < 3; ++k)
        if (!parse_int(p[k], ov[k])) return bad();
      r.overrides = ov;
    } else if (key == "Pn") {
      r.pins = std::string(val);
    } else if (key == "A") {
      r.accessories = std::string(val);
    } else if (key == "Ln") {
      long n = 0;
      if (!parse_int(val, n)) return bad();
      r.line_number = n;
    } else if (key == "MPG") {
      int n = 0;
      if (!parse_int(val, n)) return bad();
      r.mpg = n != 0;
    } else if (key == "H") {
      r.homed = std::string(val);
    } else if (key == "T") {
      int n = 0;
      if (!parse_int(val, n)) return bad();
      r.tool = n;
    }
    // Other fields (SD:, Sc:, FW:, ...) carry nothing the streamer acts on.
  }
  return r;
}

StatusReport StatusTracker::update(StatusReport r) {
  if (r.wco) wco_ = r.wco;
  if (r.overrides) ov_ = r.overrides;
  if (wco_) {
    if (r.mpos && !r.wpos) {
      Axes w{};
      for (std::size_t i = 0; i < w.size(); ++i) w[i] = (*r.mpos)[i] - (*wco_)[i];
      r.wpos = w;
    } else if (r.wpos && !r.mpos) {
      Axes m{};
      for (std::size_t i = 0; i < m.size(); ++i) m[i] = (*r.wpos)[i] + (*wco_)[i];
      r.mpos = m;
    }
  }
  if (!r.wco) r.wco = wco_;
  if (!r.overrides) r.overrides = ov_;
  last_ = r;
  return r;
}

}  // namespace cncstream::protocol
