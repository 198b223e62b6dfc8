#include "cncstream/protocol/link_model.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <stdexcept>

namespace cncstream::protocol {

gcode::StreamLink link_model(const FirmwareProfile& profile, std::optional<double> link_rate_bytes_per_s) {
  gcode::StreamLink link;
  link.bytes_per_second = profile.native_usb ? 0.0 : gcode::bytes_per_second_for_baud(profile.baud);
  if (link_rate_bytes_per_s) link.bytes_per_second = *link_rate_bytes_per_s;
  link.rx_bytes = profile.rx_buffer_size;
  link.rx_margin = profile.rx_margin;
  link.planner_blocks = static_cast<std::size_t>(std::max(1, profile.planner_blocks));
  link.blocks_per_second = profile.blocks_per_second;
  return link;
}

gcode::StreamLink grbl_default_link() {
  gcode::StreamLink link;
  link.bytes_per_second = gcode::bytes_per_second_for_baud(115200);
  return link;
}

double parse_link_rate(const std::string& text) {
  if (text == "usb") return 0.0;
  std::string number = text;
  bool baud = false;
  if (number.size() > 4 && number.compare(number.size() - 4, 4, "baud") == 0) {
    number.resize(number.size() - 4);
    baud = true;
  }
  std::size_t used = 0;
  double v = -1;
  try {
    v = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (number.empty() || used != number.size() || !(v > 0))
    throw std::invalid_argument("--link-rate '" + text +
                                "': expected bytes per second (11520), a baud rate (115200baud) or 'usb' (unbounded)");
  return baud ? gcode::bytes_per_second_for_baud(v) : v;
}

std::string describe_link(const gcode::StreamLink& link) {
  const std::string wire = link.bytes_per_second > 0
                               ? fmt::format("{:.0f} baud ({:.0f} bytes/s)", link.bytes_per_second * 10, link.bytes_per_second)
                               : std::string("native USB (unbounded)");
  std::string s = fmt::format("{}, {}-byte RX buffer, {} planner blocks", wire, link.rx_bytes, link.planner_blocks);
  if (link.blocks_per_second > 0) s += fmt::format(", {:.0f} blocks/s", link.blocks_per_second);
  return s;
}

}  // namespace cncstream::protocol
