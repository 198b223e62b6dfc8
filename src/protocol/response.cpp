#include "cncstream/protocol/response.hpp"

#include <charconv>
#include <vector>

namespace cncstream::protocol {

const char* to_string(ResponseKind k) {
  switch (k) {
    case ResponseKind::Empty: return "empty";
    case ResponseKind::Ok: return "ok";
    case ResponseKind::Error: return "error";
    case ResponseKind::Alarm: return "alarm";
    case ResponseKind::Status: return "status";
    case ResponseKind::Message: return "message";
    case ResponseKind::ParserState: return "parser-state";
    case ResponseKind::Version: return "version";
    case ResponseKind::Options: return "options";
    case ResponseKind::Feedback: return "feedback";
    case ResponseKind::StartupEcho: return "startup-echo";
    case ResponseKind::Resend: return "resend";
    case ResponseKind::MarlinError: return "marlin-error";
    case ResponseKind::Busy: return "busy";
    case ResponseKind::Other: return "other";
  }
  return "?";
}

namespace {

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

template <class Int>
bool to_int(std::string_view s, Int& out) {
  s = trim(s);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc{} && r.ptr == s.data() + s.size();
}

// Marlin's ok may carry "N<n> P<n> B<n>" and, on printers, temperatures; read
// the three counters and ignore the rest.
void parse_marlin_ok_fields(std::string_view rest, Response& r) {
  std::size_t i = 0;
  while (i < rest.size()) {
    while (i < rest.size() && rest[i] == ' ') ++i;
    std::size_t j = i;
    while (j < rest.size() && rest[j] != ' ') ++j;
    const auto tok = rest.substr(i, j - i);
    if (tok.size() >= 2) {
      long v = 0;
      if (to_int(tok.substr(1), v)) {
        if (tok[0] == 'N') r.ok_line = v;
        else if (tok[0] == 'P') r.ok_planner_free = static_cast<int>(v);
        else if (tok[0] == 'B') r.ok_buffer_free = static_cast<int>(v);
      }
    }
    i = j;
  }
}

}  // namespace

Response parse_response(std::string_view raw) {
  Response r;
  r.line = std::string(raw);
  const std::string_view line = trim(raw);
  if (line.empty()) return r;

  if (line == "ok") {
    r.kind = ResponseKind::Ok;
    return r;
  }
  if (starts_with(line, "ok ")) {
    r.kind = ResponseKind::Ok;
    parse_marlin_ok_fields(line.substr(3), r);
    return r;
  }
  if (starts_with(line, "error:")) {
    r.kind = ResponseKind::Error;
    r.body = std::string(line.substr(6));
    if (!to_int(r.body, r.code)) {
      // GRBL 0.9 and some forks send text instead of a number; keep it as an error.
      r.code = -1;
      r.parse_error = "error without a numeric code: '" + std::string(line) + "'";
    }
    return r;
  }
  if (starts_with(line, "ALARM:")) {
    r.kind = ResponseKind::Alarm;
    r.body = std::string(line.substr(6));
    if (!to_int(r.body, r.code)) {
      r.code = -1;
      r.parse_error = "alarm without a numeric code: '" + std::string(line) + "'";
    }
    return r;
  }
  if (line.front() == '<') {
    r.kind = ResponseKind::Status;
    r.status = parse_status_report(line, &r.parse_error);
    return r;
  }
  if (line.front() == '[' && line.back() == ']') {
    const auto inner = line.substr(1, line.size() - 2);
    const auto colon = inner.find(':');
    const auto tag = inner.substr(0, colon);
    r.body = colon == std::string_view::npos ? std::string() : std::string(inner.substr(colon + 1));
    if (tag == "MSG") r.kind = ResponseKind::Message;
    else if (tag == "GC") r.kind = ResponseKind::ParserState;
    else if (tag == "VER") r.kind = ResponseKind::Version;
    else if (tag == "OPT") r.kind = ResponseKind::Options;
    else {
      r.kind = ResponseKind::Feedback;
      r.body = std::string(inner);
    }
    return r;
  }
  // Startup-line reports: ">G54G20:ok", or ">G1X1:error:22" when the line failed.
  if (line.front() == '>' && line.size() >= 4 && line.substr(line.size() - 3) == ":ok") {
    r.kind = ResponseKind::StartupEcho;
    r.body = std::string(line.substr(1, line.size() - 4));
    return r;
  }
  if (const auto err = line.rfind(":error:"); line.front() == '>' && err != std::string_view::npos) {
    long n = 0;
    if (to_int(line.substr(err + 7), n)) {
      r.kind = ResponseKind::StartupEcho;
      r.body = std::string(line.substr(1, err - 1));
      r.code = static_cast<int>(n);
      return r;
    }
  }
  if (starts_with(line, "Resend:") || starts_with(line, "rs ")) {
    r.kind = ResponseKind::Resend;
    const auto num = line.substr(starts_with(line, "rs ") ? 3 : 7);
    long n = 0;
    if (!to_int(num, n)) {
      r.parse_error = "resend request without a line number: '" + std::string(line) + "'";
      r.code = -1;
    } else {
      r.code = static_cast<int>(n);
    }
    return r;
  }
  if (starts_with(line, "Error:") || starts_with(line, "!!")) {
    r.kind = ResponseKind::MarlinError;
    r.body = std::string(trim(line.substr(starts_with(line, "!!") ? 2 : 6)));
    return r;
  }
  if (starts_with(line, "echo:busy:")) {
    r.kind = ResponseKind::Busy;
    r.body = std::string(trim(line.substr(10)));
    return r;
  }
  r.kind = ResponseKind::Other;
  r.body = std::string(line);
  return r;
}

std::optional<BuildOptions> parse_build_options(std::string_view body) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  for (;;) {
    const auto p = body.find(',', start);
    parts.push_back(body.substr(start, p == std::string_view::npos ? std::string_view::npos : p - start));
    if (p == std::string_view::npos) break;
    start = p + 1;
  }
  BuildOptions o;
  o.flags = std::string(parts[0]);
  int v = 0;
  if (parts.size() >= 2) {
    if (!to_int(parts[1], v) || v <= 0) return std::nullopt;
    o.planner_blocks = v;
  }
  if (parts.size() >= 3) {
    if (!to_int(parts[2], v) || v <= 0) return std::nullopt;
    o.rx_buffer_size = v;
  }
  return o;
}

}  // namespace cncstream::protocol
