#pragma once
// The fields of the machine routes' JSON bodies, of the WebSocket jog and the
// routes' whole-number query parameters, each checked with an ApiError 400
// naming the field (docs/api-v1.md). Pure:
// the handlers call them before touching a machine, and the fuzz targets
// call them on whatever a client may send.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>

#include "cncstream/daemon/http_types.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/jog.hpp"

namespace cncstream::daemon {

// b[key]: a finite number with lo < v <= hi.
double number_field(const nlohmann::json& b, const char* key, double lo, double hi);
// b["dir"]: [x, y, z], finite, not all zero.
protocol::JogDirection jog_direction(const nlohmann::json& b);
// b["line"]: 1 to 256 printable ASCII characters (real-time bytes have their own routes).
std::string console_line(const nlohmann::json& b);
// b["axes"]: one to three of X, Y, Z, e.g. "XY".
std::string zero_axes_field(const nlohmann::json& b);
// b["command"]: an override or coolant key of the firmware profiles' [realtime] table
// (hold, reset and cycle start have their own routes with their own rules).
protocol::Realtime override_command(const nlohmann::json& b);
// b["force"]: absent (false) or a boolean.
bool force_field(const nlohmann::json& b);
// b["on"]: a boolean.
bool on_field(const nlohmann::json& b);
// A job's id in a path: 1 to 18 digits; ApiError 404 otherwise.
std::int64_t job_id_param(const std::string& s);
// An optional whole-number query parameter within [lo, hi] (`fallback` when
// absent); ApiError 400 naming it otherwise.
long long bounded_query(const Request& r, const std::string& name, long long fallback, long long lo, long long hi);

}  // namespace cncstream::daemon
