#include "cncstream/daemon/routine_bodies.hpp"

#include "cncstream/cam/cutter.hpp"
#include "cncstream/daemon/body_fields.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace detail_routine_bodies {

void require_object(const json& b) {
  if (!b.is_object()) throw ApiError{400, "bad_request", "expected a JSON object"};
}

// b[key] when present (a number within (lo, hi]), else `fallback`.
double optional_number(const json& b, const char* key, double fallback, double lo, double hi) {
  return b.contains(key) ? number_field(b, key, lo, hi) : fallback;
}

}  // namespace detail_routine_bodies

protocol::CornerProbeConfig corner_probe_body(const json& b) {
  using detail_routine_bodies::optional_number;
  detail_routine_bodies::require_object(b);
  protocol::CornerProbeConfig c;
  if (!b.contains("axes") || !b.at("axes").is_string())
    throw ApiError{400, "bad_request", "axes: required, one of xyz, xy, z"};
  try {
    c.axes = protocol::parse_corner_axes(b.at("axes").get<std::string>());
  } catch (const std::invalid_argument& e) {
    throw ApiError{400, "bad_request", std::string("axes: ") + e.what()};
  }
  if (b.contains("tool")) {
    if (!b.at("tool").is_string()) throw ApiError{400, "bad_request", "tool: a cutter spec such as flat:6"};
    try {
      c.tool_radius = cam::parse_cutter_spec(b.at("tool").get<std::string>()).radius;
    } catch (const std::invalid_argument& e) {
      throw ApiError{400, "bad_request", std::string("tool: ") + e.what()};
    }
  } else if (c.axes != protocol::CornerAxes::Z) {
    throw ApiError{400, "bad_request", "tool: required to probe X or Y (its radius offsets the edges), e.g. flat:6"};
  }
  if (b.contains("plate")) {
    const json& p = b.at("plate");
    if (!p.is_object()) throw ApiError{400, "bad_request", "plate: an object {thickness, lip, size}"};
    c.plate.thickness = optional_number(p, "thickness", c.plate.thickness, 0, 100);
    c.plate.lip = optional_number(p, "lip", c.plate.lip, -1e-12, 100);
    c.plate.size = optional_number(p, "size", c.plate.size, 0, 1000);
  }
  c.z_travel = optional_number(b, "z_travel", c.z_travel, 0, 500);
  c.fast_feed = optional_number(b, "fast_feed", c.fast_feed, 0, 5000);
  c.slow_feed = optional_number(b, "slow_feed", c.slow_feed, 0, 1000);
  try {
    protocol::validate(c);
  } catch (const std::invalid_argument& e) {
    throw ApiError{400, "bad_request", e.what()};
  }
  return c;
}

OutlineBody outline_body(const json& b) {
  using detail_routine_bodies::optional_number;
  detail_routine_bodies::require_object(b);
  OutlineBody o;
  if (!b.contains("job")) throw ApiError{400, "bad_request", "job: required, the job whose program is traced"};
  const double id = number_field(b, "job", 0, 1e15);
  if (id != static_cast<double>(static_cast<std::int64_t>(id))) throw ApiError{400, "bad_request", "job: a job's id"};
  o.job = static_cast<std::int64_t>(id);
  o.feed = optional_number(b, "feed", o.feed, 0, 50000);
  if (b.contains("safe_z")) o.safe_z = number_field(b, "safe_z", -1e4, 1e4);
  if (b.contains("shape")) {
    const json& s = b.at("shape");
    if (!s.is_string() || (s != "hull" && s != "box")) throw ApiError{400, "bad_request", "shape: hull or box"};
    o.box = s == "box";
  }
  return o;
}

}  // namespace cncstream::daemon
