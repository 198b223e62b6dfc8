#pragma once
// The JSON bodies of the routines outside a job that set work zero or check
// the stock (docs/api-v1.md): corner probing and the outline. Pure, each field
// checked with an ApiError 400 naming it before anything moves.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>

#include "cncstream/protocol/corner_probe.hpp"

namespace cncstream::daemon {

// {"axes": "xyz"|"xy"|"z", "tool": "flat:6" (the cutter in the spindle: its
// radius offsets X and Y), "plate": {"thickness", "lip", "size"} (mm; the
// machine's corner plate), "z_travel", "fast_feed", "slow_feed"}. `tool` is
// required when X or Y is probed: a wrong radius is a wrong zero.
protocol::CornerProbeConfig corner_probe_body(const nlohmann::json& b);

// {"job": ID (its program's extent), "feed": mm/min (default 1000),
// "safe_z": work Z (default: the program's highest Z), "shape": "hull"|"box"}.
struct OutlineBody {
  std::int64_t job = 0;
  double feed = 1000;
  std::optional<double> safe_z;
  bool box = false;
};
OutlineBody outline_body(const nlohmann::json& b);

}  // namespace cncstream::daemon
