#include "cncstream/daemon/body_fields.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {
[[noreturn]] void bad(std::string message) { throw ApiError{400, "bad_request", std::move(message)}; }

}  // namespace

double number_field(const json& b, const char* key, double lo, double hi) {
  if (!b.is_object() || !b.contains(key) || !b.at(key).is_number()) bad(cat({key, ": required, a number"}));
  const double v = b.at(key).get<double>();
  if (!std::isfinite(v) || !(v > lo) || !(v <= hi))
    bad(cat({key, ": must be > ", num_text(lo), " and <= ", num_text(hi)}));
  return v;
}

protocol::JogDirection jog_direction(const json& b) {
  if (!b.is_object() || !b.contains("dir") || !b.at("dir").is_array() || b.at("dir").size() != 3)
    bad("dir: expected [x, y, z]");
  const json& dir = b.at("dir");
  protocol::JogDirection d;
  double n = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!dir[i].is_number() || !std::isfinite(dir[i].get<double>())) bad("dir: expected 3 finite numbers");
    d.v[i] = dir[i].get<double>();
    n += std::abs(d.v[i]);
  }
  if (n == 0) bad("dir: all zero");
  return d;
}

std::string console_line(const json& b) {
  if (!b.is_object() || !b.contains("line") || !b.at("line").is_string()) bad("line: required, a string");
  std::string line = b.at("line").get<std::string>();
  if (line.empty() || line.size() > 256) bad("line: 1 to 256 characters");
  for (std::size_t i = 0; i < line.size(); ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    if (c < 0x20 || c > 0x7e)
      bad(cat({"line: byte ", std::to_string(i), " is not printable ASCII (real-time bytes have their own routes)"}));
  }
  return line;
}

std::string zero_axes_field(const json& b) {
  if (!b.is_object() || !b.contains("axes") || !b.at("axes").is_string()) bad("axes: required, e.g. \"XY\"");
  std::string axes = b.at("axes").get<std::string>();
  if (axes.empty() || axes.size() > 3 || axes.find_first_not_of("XYZ") != std::string::npos)
    bad("axes: letters from X, Y, Z");
  return axes;
}

protocol::Realtime override_command(const json& b) {
  if (!b.is_object() || !b.contains("command") || !b.at("command").is_string()) bad("command: required");
  const std::string k = b.at("command").get<std::string>();
  const bool override_key = k.rfind("feed_ov_", 0) == 0 || k.rfind("rapid_ov_", 0) == 0 ||
                            k.rfind("spindle_ov_", 0) == 0 || k == "spindle_stop" || k == "flood_toggle" ||
                            k == "mist_toggle";
  const auto rt = protocol::realtime_from_key(k);
  if (!rt || !override_key) bad(cat({"command: '", k.substr(0, 40), "' is not an override"}));
  return *rt;
}

bool force_field(const json& b) {
  if (!b.is_object()) bad("expected a JSON object");
  if (!b.contains("force")) return false;
  if (!b.at("force").is_boolean()) bad("force: expected true or false");
  return b.at("force").get<bool>();
}

bool on_field(const json& b) {
  if (!b.is_object() || !b.contains("on") || !b.at("on").is_boolean()) bad("on: required, true or false");
  return b.at("on").get<bool>();
}

std::int64_t job_id_param(const std::string& s) {
  if (s.empty() || s.size() > 18 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw ApiError{404, "not_found", cat({"no job '", s.substr(0, 64), "'"})};
  return std::stoll(s);
}

long long bounded_query(const Request& r, const std::string& name, long long fallback, long long lo, long long hi) {
  const auto v = r.query_value(name);
  if (!v) return fallback;
  const auto bad = [&] {
    return ApiError{400, "bad_request", cat({name, ": a whole number from ", std::to_string(lo), " to ", std::to_string(hi),
                                             " (got '", v->substr(0, 24), "')"})};
  };
  if (v->empty() || v->size() > 12 || v->find_first_not_of("0123456789") != std::string::npos) throw bad();
  const long long n = std::stoll(*v);
  if (n < lo || n > hi) throw bad();
  return n;
}

}  // namespace cncstream::daemon
