#pragma once
// The link a firmware profile describes (baud or native USB, RX buffer,
// planner depth, planning rate) as the numbers the time estimate and the
// feed limit work with. A `--link-rate` given on the command line replaces
// the profile's bytes per second.
#include <optional>
#include <string>

#include "cncstream/gcode/stream_link.hpp"
#include "cncstream/protocol/firmware_profile.hpp"

namespace cncstream::protocol {

gcode::StreamLink link_model(const FirmwareProfile& profile, std::optional<double> link_rate_bytes_per_s = {});

// GRBL 1.1 on an Arduino's USB-serial bridge: 115,200 baud, 128-byte RX,
// 15 blocks (the default when no profile is known yet).
gcode::StreamLink grbl_default_link();

// "11520" (bytes/s), "115200baud", "usb" (unbounded). Throws
// std::invalid_argument naming the text.
double parse_link_rate(const std::string& text);

// "115,200 baud (11,520 bytes/s), 128-byte RX buffer, 15 planner blocks".
std::string describe_link(const gcode::StreamLink& link);

}  // namespace cncstream::protocol
